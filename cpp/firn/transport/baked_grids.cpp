#include "firn/transport/baked_grids.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/error.h"

namespace firn {

openvdb::GridPtrVec BakedGrids::grids() const { return openvdb::GridPtrVec(source.begin(), source.end()); }

BakedGrids BakedGrids::find(const openvdb::GridPtrVec &grids) {
    BakedGrids out;
    for (std::size_t i = 0; i < kNames.size(); ++i) {
        for (const auto &grid : grids)
            if (grid->getName() == kNames[i]) out.source[i] = openvdb::gridPtrCast<openvdb::Vec3fGrid>(grid);
        if (!out.source[i]) throw InvalidArgument(std::string("no Vec3f grid named ") + kNames[i]);
    }
    return out;
}

namespace {
int floorDiv(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
}  // namespace

std::array<openvdb::Vec3fTree::Ptr, BakedGrids::kCount> coarsenedSources(const openvdb::BoolTree &fineTopology,
                                                                         const FineValuesReaders &newReader,
                                                                         const openvdb::FloatTree &density, int factor) {
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
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            std::array<Vec3Tree::LeafNodeType *, kCount> leaf;
            leaf[0] = &leaves.leaf(l);
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

Rgb renderBaked(const Scene &scene, const BakedGrids &baked, const Ray &ray) {
    double tMax = std::numeric_limits<double>::infinity();
    if (const auto hit = scene.occluders->caster().intersect(glm::vec3(ray.origin), glm::vec3(ray.direction)))
        tMax = hit->distance;
    // Steps of 1/32 voxel resolve the steepest density ramp (one voxel) to well under 1 %.
    return BakedRadiance(scene, baked).along(ray, tMax, 1.0 / 32.0);
}

}  // namespace firn
