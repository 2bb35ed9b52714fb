#include "firn/transport/baked_grids.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/bake_thin_snow.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/error.h"
#include "firn/util/work_check.h"

namespace firn {

openvdb::GridPtrVec BakedGrids::grids() const {
    openvdb::GridPtrVec out(source.begin(), source.end());
    if (scatter) out.push_back(scatter);
    return out;
}

bool BakedGrids::isBaked(const std::string &name) {
    return name == kScatterName || std::find(kNames.begin(), kNames.end(), name) != kNames.end();
}

BakedGrids BakedGrids::find(const openvdb::GridPtrVec &grids) {
    BakedGrids out;
    for (std::size_t i = 0; i < kNames.size(); ++i) {
        for (const auto &grid : grids)
            if (grid->getName() == kNames[i]) out.source[i] = openvdb::gridPtrCast<openvdb::Vec3fGrid>(grid);
        if (!out.source[i]) throw InvalidArgument(std::string("no Vec3f grid named ") + kNames[i]);
    }
    for (const auto &grid : grids)
        if (grid->getName() == kScatterName) out.scatter = openvdb::gridPtrCast<openvdb::FloatGrid>(grid);
    return out;
}

namespace {
int floorDiv(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
}  // namespace

std::array<openvdb::Vec3fTree::Ptr, BakedGrids::kCount> coarsenedSources(const openvdb::BoolTree &fineTopology,
                                                                         const FineValuesReaders &newReader,
                                                                         const openvdb::FloatTree &density, int factor,
                                                                         const SubProgress &progress) {
    if (factor < 2) throw InvalidArgument("source grids: coarsening factor must be at least 2");
    using Vec3Tree = openvdb::Vec3fTree;
    constexpr std::size_t kCount = BakedGrids::kCount;
    // The coarse voxels over the fine ones.
    openvdb::BoolTree coarse(false);
    {
        openvdb::tree::ValueAccessor<openvdb::BoolTree> on(coarse);
        for (auto it = fineTopology.cbeginValueOn(); it; ++it) {
            if (!it.isVoxelValue()) throw InvalidArgument("source grids: tiles are not supported");
            const openvdb::Coord c = it.getCoord();
            on.setValueOn(openvdb::Coord(floorDiv(c.x(), factor), floorDiv(c.y(), factor), floorDiv(c.z(), factor)));
        }
    }
    std::array<Vec3Tree::Ptr, kCount> trees;
    for (auto &tree : trees) tree = std::make_shared<Vec3Tree>(coarse, openvdb::Vec3f(0.0f), openvdb::TopologyCopy());
    openvdb::tree::LeafManager<Vec3Tree> leaves(*trees[0]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> rho(density);
        auto in = newReader();
        WorkCheck work(progress);
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            std::array<Vec3Tree::LeafNodeType *, kCount> leaf;
            leaf[0] = &leaves.leaf(l);
            // Each coarse voxel reads factor^3 fine ones.
            work.add(WorkCheck::kVoxel * std::uint64_t(factor * factor * factor) * leaf[0]->onVoxelCount());
            for (std::size_t g = 1; g < kCount; ++g) leaf[g] = trees[g]->probeLeaf(leaf[0]->origin());
            for (auto it = leaf[0]->beginValueOn(); it; ++it) {
                const openvdb::Coord C = it.getCoord();
                std::array<openvdb::Vec3d, kCount> weighted, extended;
                weighted.fill(openvdb::Vec3d(0.0)), extended.fill(openvdb::Vec3d(0.0));
                double weight = 0.0;
                int outside = 0;
                for (int i = 0; i < factor; ++i)
                    for (int j = 0; j < factor; ++j)
                        for (int k = 0; k < factor; ++k) {
                            const openvdb::Coord c(C.x() * factor + i, C.y() * factor + j, C.z() * factor + k);
                            const double w = rho.getValue(c);
                            const BakedGrids::Values v = in(c);
                            if (w <= 0.0 && v[0] == openvdb::Vec3f(0.0f)) continue;  // no snow, no extended value: a ring voxel
                            for (std::size_t g = 0; g < kCount; ++g) {
                                const openvdb::Vec3d value(v[g]);
                                weighted[g] += w * value;
                                extended[g] += value;
                            }
                            weight += std::max(w, 0.0);
                            outside += w <= 0.0;
                        }
                for (std::size_t g = 0; g < kCount; ++g) {
                    const openvdb::Vec3d v = weight > 0.0 ? weighted[g] / weight
                                             : outside    ? extended[g] / outside
                                                          : openvdb::Vec3d(0.0);
                    leaf[g]->setValueOnly(it.pos(), openvdb::Vec3f(v));
                }
            }
        }
    });
    for (auto &tree : trees)
        openvdb::tools::dilateActiveValues(*tree, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::EXPAND_TILES);
    return trees;
}

SourceGridsSampler::SourceGridsSampler(const Medium &medium, const BakedGrids &baked)
    : source_{Reader(baked.source[0]->tree()), Reader(baked.source[1]->tree()), Reader(baked.source[2]->tree()),
              Reader(baked.source[3]->tree()), Reader(baked.source[4]->tree()), Reader(baked.source[5]->tree())},
      sourceIndexPerDensityIndex_(medium.voxelSize() / baked.source[0]->voxelSize()[0]) {}

BakedGrids::Values SourceGridsSampler::operator()(const openvdb::Vec3d &ijk) {
    const openvdb::Vec3d at = ijk * sourceIndexPerDensityIndex_;
    BakedGrids::Values out;
    for (std::size_t g = 0; g < out.size(); ++g) out[g] = openvdb::tools::BoxSampler::sample(source_[g], at);
    return out;
}

BakedRadiance::BakedRadiance(const Scene &scene, const BakedGrids &baked)
    : scene_(scene), marcher_(*scene.medium), source_(*scene.medium, baked) {}

Rgb bakedSourceToward(const BakedGrids::Values &source, const glm::dvec3 &w) {
    // source: l0, l1 per axis, p0 (RGB), then p1
    const glm::dvec3 peak = peakRadiance(glm::dvec3(source[4][0], source[4][1], source[4][2]),
                                         glm::dvec3(source[5][0], source[5][1], source[5][2]), w);
    Rgb S;
    for (int c = 0; c < 3; ++c)
        S[c] = lobeRadiance(source[0][c], glm::dvec3(source[1][c], source[2][c], source[3][c]), w) + peak[c];
    return S;
}

Rgb renderBaked(const Scene &scene, const BakedGrids &baked, const Ray &ray) {
    double tMax = std::numeric_limits<double>::infinity();
    if (const auto hit = scene.occluders->caster().intersect(glm::vec3(ray.origin), glm::vec3(ray.direction)))
        tMax = hit->distance;
    // Steps of 1/32 voxel resolve the steepest density ramp (one voxel) to well under 1 %.
    return BakedRadiance(scene, baked).along(ray, tMax, 1.0 / 32.0);
}

openvdb::BoolTree::Ptr scatterMask(const Medium &medium, const std::vector<openvdb::Coord> &candidates,
                                   double thinDepth) {
    const double depthPerDensity = medium.optics().extinctionPerDensity * medium.voxelSize();
    auto mask = std::make_shared<openvdb::BoolTree>(false);
    openvdb::tree::ValueAccessor<openvdb::BoolTree> on(*mask);
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> rho(medium.density().tree());
    for (const openvdb::Coord &c : candidates)
        if (const float value = rho.getValue(c); value > 0.0f && depthPerDensity * value < thinDepth)
            on.setValueOn(c, true);
    return mask;
}

openvdb::BoolTree::Ptr scatterMask(const Scene &scene, double thinDepth, bool tracedOnly) {
    const Medium &medium = *scene.medium;
    if (!tracedOnly) {
        std::vector<openvdb::Coord> snow;
        for (auto it = medium.density().cbeginValueOn(); it; ++it) snow.push_back(it.getCoord());
        return scatterMask(medium, snow, thinDepth);
    }
    const SnowTopology topo = buildSnowTopology(medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    return scatterMask(medium, bake::scatteredVoxels(medium, bake::thinVoxels(medium, topo)), thinDepth);
}

openvdb::FloatTree::Ptr scatteredDensity(const openvdb::BoolTree &scattered, const openvdb::FloatTree &density,
                                         int factor) {
    if (factor < 1) throw InvalidArgument("scattered density: coarsening factor must be at least 1");
    auto coarse = std::make_shared<openvdb::FloatTree>(0.0f);
    openvdb::tree::ValueAccessor<openvdb::FloatTree> out(*coarse);
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> rho(density);
    for (auto it = scattered.cbeginValueOn(); it; ++it) {
        if (!it.isVoxelValue()) throw InvalidArgument("scattered density: tiles of scattered voxels are not supported");
        const openvdb::Coord c = it.getCoord();
        const float value = rho.getValue(c);  // kg/m^3
        if (!(value > 0.0f)) continue;
        // The coarse voxels J with |c - factor J| <= factor along each axis: ceil(c / factor) - 1 to floor + 1.
        const openvdb::Coord lo(floorDiv(c.x() + factor - 1, factor) - 1, floorDiv(c.y() + factor - 1, factor) - 1,
                                floorDiv(c.z() + factor - 1, factor) - 1);
        const openvdb::Coord hi(floorDiv(c.x(), factor) + 1, floorDiv(c.y(), factor) + 1, floorDiv(c.z(), factor) + 1);
        for (int x = lo.x(); x <= hi.x(); ++x)
            for (int y = lo.y(); y <= hi.y(); ++y)
                for (int z = lo.z(); z <= hi.z(); ++z)
                    if (const openvdb::Coord J(x, y, z); !(out.getValue(J) >= value)) out.setValue(J, value);
    }
    return coarse;
}

double scatteredShare(double density, double scatteredDensity) {
    return density > 0.0 ? std::min(density, scatteredDensity) / density : 0.0;
}

std::vector<RadianceEstimate> renderScatteringWhereThin(const MonteCarloReference &reference, const BakedGrids &baked,
                                                        const std::vector<Ray> &rays, int samples, std::uint64_t seed,
                                                        double thinDepth, int bounces, bool tracedOnly,
                                                        int shareScale) {
    const Scene &scene = reference.scene();
    const Medium &medium = *scene.medium;
    const openvdb::FloatTree::Ptr scattered =
        scatteredDensity(*scatterMask(scene, thinDepth, tracedOnly), medium.density().tree(), shareScale);
    return estimateMixed(reference, rays, samples, seed, [&] {
        using FloatAccessor = openvdb::tree::ValueAccessor<const openvdb::FloatTree>;
        auto scatteredAt = std::make_shared<FloatAccessor>(*scattered);
        auto rho = std::make_shared<Medium::DensitySampler>(medium);
        auto sampler = std::make_shared<SourceGridsSampler>(medium, baked);
        auto marcher = std::make_shared<Medium::ColumnMarcher>(medium);
        // The share at a point of density `density` (read there by the caller), kg/m^3.
        auto shareAt = [scatteredAt, shareScale](const openvdb::Vec3d &ijk, double density) {
            return scatteredShare(density, openvdb::tools::BoxSampler::sample(*scatteredAt, ijk / double(shareScale)));
        };
        auto indexOf = [&medium](const glm::dvec3 &p) {
            const glm::dvec3 ijk = medium.worldToIndex(p);
            return openvdb::Vec3d(ijk.x, ijk.y, ijk.z);
        };
        MixedRender mixed;
        mixed.bounces = bounces;
        mixed.scatterShare = [indexOf, rho, shareAt](const glm::dvec3 &p) {
            const openvdb::Vec3d ijk = indexOf(p);
            return shareAt(ijk, rho->at(ijk));
        };
        mixed.emittedAt = [indexOf, rho, sampler, shareAt](const glm::dvec3 &p, const glm::dvec3 &w) {
            const openvdb::Vec3d ijk = indexOf(p);
            return (1.0 - shareAt(ijk, rho->at(ijk))) * bakedSourceToward((*sampler)(ijk), w);
        };
        mixed.emittedAlong = [&scene, sampler, marcher, shareAt](const Ray &camera, double tMax) {
            // The march has just read the density at ijk: its sampler holds that cell (no second tree walk).
            auto unshared = [&](const openvdb::Vec3d &ijk) {
                BakedGrids::Values v = (*sampler)(ijk);
                const float keep = float(1.0 - shareAt(ijk, marcher->densityAt(ijk)));
                for (auto &value : v) value *= keep;  // the lobes are linear in their values
                return v;
            };
            return bakedRadianceAlong(scene, *marcher, unshared, camera, tMax, 1.0 / 32.0);
        };
        return mixed;
    });
}

}  // namespace firn
