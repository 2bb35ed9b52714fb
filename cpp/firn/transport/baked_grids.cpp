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

openvdb::BoolTree::Ptr litVoxels(const openvdb::Vec3fTree &source) {
    auto lit = std::make_shared<openvdb::BoolTree>(false);
    openvdb::tree::ValueAccessor<openvdb::BoolTree> set(*lit);
    for (auto it = source.cbeginValueOn(); it; ++it)
        if (*it != openvdb::Vec3f(0.0f)) set.setValue(it.getCoord(), true);
    return lit;
}

namespace {

// coarsenedSource over the active voxels of `fine` (any tree), reading their values through newReader() (one reader
// per thread).
template <typename FineTree, typename NewReader>
openvdb::Vec3fTree::Ptr coarsened(const FineTree &fine, const NewReader &newReader, const openvdb::BoolTree &lit,
                                  const openvdb::FloatTree &density, int factor) {
    if (factor < 2) throw InvalidArgument("source grids: coarsening factor must be at least 2");
    using Vec3Tree = openvdb::Vec3fTree;
    // The coarse voxels over the fine ones.
    auto tree = std::make_shared<Vec3Tree>(openvdb::Vec3f(0.0f));
    {
        openvdb::tree::ValueAccessor<Vec3Tree> coarse(*tree);
        for (auto it = fine.cbeginValueOn(); it; ++it) {
            if (!it.isVoxelValue()) throw InvalidArgument("source grids: tiles are not supported");
            const openvdb::Coord c = it.getCoord();
            coarse.setValueOn(openvdb::Coord(floorDiv(c.x(), factor), floorDiv(c.y(), factor), floorDiv(c.z(), factor)));
        }
    }
    openvdb::tree::LeafManager<Vec3Tree> leaves(*tree);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> rho(density);
        auto in = newReader();
        openvdb::tree::ValueAccessor<const openvdb::BoolTree> isLit(lit);
        for (std::size_t l = range.begin(); l != range.end(); ++l)
            for (auto it = leaves.leaf(l).beginValueOn(); it; ++it) {
                const openvdb::Coord C = it.getCoord();
                openvdb::Vec3d weighted(0.0), extended(0.0);
                double weight = 0.0;
                int outside = 0;
                for (int i = 0; i < factor; ++i)
                    for (int j = 0; j < factor; ++j)
                        for (int k = 0; k < factor; ++k) {
                            const openvdb::Coord c(C.x() * factor + i, C.y() * factor + j, C.z() * factor + k);
                            const double w = rho.getValue(c);
                            if (w <= 0.0 && !isLit.getValue(c)) continue;  // no snow, no extended value: a ring voxel
                            const openvdb::Vec3d v(in(c));
                            weighted += w * v;
                            extended += v;
                            weight += std::max(w, 0.0);
                            outside += w <= 0.0;
                        }
                const openvdb::Vec3d v = weight > 0.0 ? weighted / weight : outside ? extended / outside : openvdb::Vec3d(0.0);
                it.setValue(openvdb::Vec3f(v));
            }
    });
    openvdb::tools::dilateActiveValues(*tree, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::EXPAND_TILES);
    return tree;
}

}  // namespace

openvdb::Vec3fTree::Ptr coarsenedSource(const openvdb::Vec3fTree &fine, const openvdb::BoolTree &lit,
                                        const openvdb::FloatTree &density, int factor) {
    const auto newReader = [&] {
        return [in = openvdb::tree::ValueAccessor<const openvdb::Vec3fTree>(fine)](const openvdb::Coord &c) mutable {
            return in.getValue(c);
        };
    };
    return coarsened(fine, newReader, lit, density, factor);
}

openvdb::Vec3fTree::Ptr coarsenedSource(const openvdb::BoolTree &fineTopology, const FineSourceReaders &newReader,
                                        const openvdb::BoolTree &lit, const openvdb::FloatTree &density, int factor) {
    return coarsened(fineTopology, newReader, lit, density, factor);
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
