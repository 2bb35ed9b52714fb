#include "firn/transport/baked_grids.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/source_lobe.h"
#include "firn/util/error.h"

namespace firn {

openvdb::GridPtrVec BakedGrids::grids() const { return {source[0], source[1], source[2], source[3]}; }

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

BakedGrids coarsened(const BakedGrids &fine, const openvdb::FloatGrid &density, int factor) {
    if (factor < 1) throw InvalidArgument("source grids: coarsening factor must be at least 1");
    if (factor == 1) return fine;
    using Vec3Tree = openvdb::Vec3fTree;
    // The coarse voxels over the fine ones, all four grids sharing them.
    auto topology = std::make_shared<Vec3Tree>(openvdb::Vec3f(0.0f));
    {
        openvdb::tree::ValueAccessor<Vec3Tree> coarse(*topology);
        for (auto it = fine.source[0]->tree().cbeginValueOn(); it; ++it) {
            if (!it.isVoxelValue()) throw InvalidArgument("source grids: tiles are not supported");
            const openvdb::Coord c = it.getCoord();
            coarse.setValueOn(openvdb::Coord(floorDiv(c.x(), factor), floorDiv(c.y(), factor), floorDiv(c.z(), factor)));
        }
    }
    BakedGrids out;
    std::array<std::shared_ptr<Vec3Tree>, 4> trees;
    for (auto &tree : trees) tree = std::make_shared<Vec3Tree>(*topology);
    openvdb::tree::LeafManager<Vec3Tree> leaves(*trees[0]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> rho(density.tree());
        using Reader = openvdb::tree::ValueAccessor<const Vec3Tree>;
        std::array<Reader, 4> in{Reader(fine.source[0]->tree()), Reader(fine.source[1]->tree()),
                                 Reader(fine.source[2]->tree()), Reader(fine.source[3]->tree())};
        using Writer = openvdb::tree::ValueAccessor<Vec3Tree>;
        std::array<Writer, 4> write{Writer(*trees[0]), Writer(*trees[1]), Writer(*trees[2]), Writer(*trees[3])};
        for (std::size_t l = range.begin(); l != range.end(); ++l)
            for (auto it = leaves.leaf(l).cbeginValueOn(); it; ++it) {
                const openvdb::Coord C = it.getCoord();
                std::array<openvdb::Vec3d, 4> weighted{}, extended{};
                double weight = 0.0;
                int outside = 0;
                for (int i = 0; i < factor; ++i)
                    for (int j = 0; j < factor; ++j)
                        for (int k = 0; k < factor; ++k) {
                            const openvdb::Coord c(C.x() * factor + i, C.y() * factor + j, C.z() * factor + k);
                            const double w = rho.getValue(c);
                            const bool lit = in[0].getValue(c) != openvdb::Vec3f(0.0f);
                            if (w <= 0.0 && !lit) continue;  // no snow, no extended value: a ring voxel
                            for (int g = 0; g < 4; ++g) {
                                const openvdb::Vec3d v(in[g].getValue(c));
                                weighted[g] += w * v;
                                extended[g] += v;
                            }
                            weight += std::max(w, 0.0);
                            outside += w <= 0.0;
                        }
                for (int g = 0; g < 4; ++g) {
                    const openvdb::Vec3d v = weight > 0.0 ? weighted[g] / weight : outside ? extended[g] / outside : openvdb::Vec3d(0.0);
                    write[g].setValueOnly(C, openvdb::Vec3f(v));
                }
            }
    });
    for (std::size_t g = 0; g < 4; ++g) {
        openvdb::tools::dilateActiveValues(*trees[g], 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::EXPAND_TILES);
        auto grid = openvdb::Vec3fGrid::create(trees[g]);
        grid->setTransform(density.transform().copy());
        grid->transform().preScale(double(factor));
        grid->setName(fine.source[g]->getName());
        grid->setVectorType(fine.source[g]->getVectorType());
        for (auto meta = fine.source[g]->beginMeta(); meta != fine.source[g]->endMeta(); ++meta)
            grid->insertMeta(meta->first, *meta->second);
        out.source[g] = grid;
    }
    return out;
}

BakedRadiance::BakedRadiance(const Scene &scene, const BakedGrids &baked)
    : scene_(scene),
      marcher_(*scene.medium),
      density_(scene.medium->accessor()),
      source_{Reader(baked.source[0]->tree()), Reader(baked.source[1]->tree()), Reader(baked.source[2]->tree()),
              Reader(baked.source[3]->tree())},
      sourceIndexPerDensityIndex_(scene.medium->voxelSize() / baked.source[0]->voxelSize()[0]) {}

Rgb BakedRadiance::along(const Ray &ray, double tMax, double step) {
    const double k = scene_.medium->optics().extinctionPerDensity;
    const glm::dvec3 w = -ray.direction;  // towards the viewer
    Rgb radiance(0.0);
    double transmittance = 1.0;
    marcher_.march(ray.origin, ray.direction, tMax, step, [&](const openvdb::Vec3d &ijk, double dt) {
        const double sigmaT = k * openvdb::tools::BoxSampler::sample(density_, ijk);
        if (sigmaT <= 0.0) return true;
        const openvdb::Vec3d at = ijk * sourceIndexPerDensityIndex_;
        const openvdb::Vec3f l0 = openvdb::tools::BoxSampler::sample(source_[0], at);
        std::array<openvdb::Vec3f, 3> l1;  // per axis, RGB
        for (int a = 0; a < 3; ++a) l1[a] = openvdb::tools::BoxSampler::sample(source_[1 + a], at);
        Rgb S;
        for (int c = 0; c < 3; ++c) S[c] = lobeRadiance(l0[c], glm::dvec3(l1[0][c], l1[1][c], l1[2][c]), w);
        const double opacity = 1.0 - std::exp(-sigmaT * dt);
        radiance += transmittance * opacity * S;
        transmittance *= 1.0 - opacity;
        return transmittance > 1e-6;
    });
    return radiance;
}

Rgb renderBaked(const Scene &scene, const BakedGrids &baked, const Ray &ray) {
    double tMax = std::numeric_limits<double>::infinity();
    if (const auto hit = scene.occluders->caster().intersect(glm::vec3(ray.origin), glm::vec3(ray.direction)))
        tMax = hit->distance;
    // Steps of 1/32 voxel resolve the steepest density ramp (one voxel) to well under 1 %.
    return BakedRadiance(scene, baked).along(ray, tMax, 1.0 / 32.0);
}

}  // namespace firn
