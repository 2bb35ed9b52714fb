#include "firn/transport/joint_medium.h"

#include <cmath>

#include <openvdb/tools/Composite.h>
#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tools/Morphology.h>

#include "firn/util/error.h"

namespace firn {

namespace {

// `density` resampled trilinearly onto the voxels of `target` (its transform), another object's voxels.
openvdb::FloatGrid::Ptr resampledOnto(const openvdb::FloatGrid &density, const openvdb::GridBase &target) {
    openvdb::FloatGrid::Ptr out = openvdb::FloatGrid::create(0.0f);
    out->setTransform(target.transform().copy());
    openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(density, *out);
    return out;
}

// The object's active voxels grown (in its own voxels) to cover every point within `reach` m of one of them.
openvdb::BoolTree::Ptr reachedVoxels(const openvdb::FloatGrid &density, double reach) {
    auto mask = openvdb::BoolTree::Ptr(new openvdb::BoolTree(density.tree(), false, openvdb::TopologyCopy()));
    const int grow = int(std::ceil(reach / density.voxelSize()[0])) + 1;  // +1: voxel centres rounded below
    openvdb::tools::dilateActiveValues(*mask, grow, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::EXPAND_TILES);
    return mask;
}

// The voxels of a union's grid (in its own index space) whose centre falls in one of the reached voxels. Leaves
// wholly outside the reached voxels' box are skipped: a spray's lumps keep a few of the snow's leaves.
openvdb::BoolTree::Ptr keptVoxels(const openvdb::Vec3fGrid &source, const openvdb::FloatGrid &density,
                                  const openvdb::BoolTree &reached) {
    auto kept = openvdb::BoolTree::Ptr(new openvdb::BoolTree(false));
    openvdb::CoordBBox reachedBox;
    if (!reached.evalActiveVoxelBoundingBox(reachedBox)) return kept;
    const openvdb::BBoxd reachedWorld = density.transform().indexToWorld(reachedBox);
    openvdb::tree::ValueAccessor<const openvdb::BoolTree> isReached(reached);
    openvdb::tree::ValueAccessor<openvdb::BoolTree> keep(*kept);
    for (auto leaf = source.tree().cbeginLeaf(); leaf; ++leaf) {
        if (!source.transform().indexToWorld(leaf->getNodeBoundingBox()).hasOverlap(reachedWorld)) continue;
        for (auto it = leaf->cbeginValueOn(); it; ++it) {
            const openvdb::Vec3d world = source.indexToWorld(it.getCoord());
            if (isReached.isValueOn(openvdb::Coord::round(density.worldToIndex(world)))) keep.setValueOn(it.getCoord());
        }
    }
    return kept;
}

openvdb::Vec3fGrid::Ptr keptPart(const openvdb::Vec3fGrid &joint, const openvdb::BoolTree &kept) {
    openvdb::Vec3fGrid::Ptr out = joint.copyWithNewTree();
    auto from = joint.getConstAccessor();
    auto to = out->getAccessor();
    for (auto it = kept.cbeginValueOn(); it; ++it) to.setValue(it.getCoord(), from.getValue(it.getCoord()));
    return out;
}

}  // namespace

openvdb::FloatGrid::Ptr unionDensity(const std::vector<openvdb::FloatGrid::ConstPtr> &densities) {
    if (densities.empty()) throw InvalidArgument("a joint bake needs at least one density grid");
    openvdb::FloatGrid::Ptr sum = densities.front()->deepCopy();
    for (std::size_t i = 1; i < densities.size(); ++i) {
        const openvdb::FloatGrid::Ptr other = densities[i]->transform() == sum->transform()
                                                  ? densities[i]->deepCopy()
                                                  : resampledOnto(*densities[i], *sum);
        openvdb::tools::compSum(*sum, *other);  // takes other's nodes
    }
    return sum;
}

BakedGrids bakedGridsOf(const BakedGrids &joint, const openvdb::FloatGrid &density) {
    const double reach = density.voxelSize()[0] + joint.source[0]->voxelSize()[0];
    const openvdb::BoolTree::Ptr reached = reachedVoxels(density, reach);
    BakedGrids out;
    const openvdb::BoolTree::Ptr kept = keptVoxels(*joint.source[0], density, *reached);
    for (std::size_t k = 0; k < BakedGrids::kCount; ++k) {
        out.source[k] = keptPart(*joint.source[k], *kept);
        openvdb::tools::dilateActiveValues(out.source[k]->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                           openvdb::tools::EXPAND_TILES);  // the ring: its new voxels hold zeros
    }
    if (joint.scatter) {  // the object's own density over the union's scattered voxels; none where it has none
        if (!joint.scattered) throw InvalidArgument("a joint bake's scatter grid needs its scattered voxels");
        const bool same = density.transform() == joint.scattered->transform();
        const openvdb::FloatGrid::Ptr resampled = same ? nullptr : resampledOnto(density, *joint.scattered);
        const openvdb::FloatTree &own = same ? density.tree() : resampled->tree();
        out.scatter = joint.scatter->copyWithNewTree();
        out.scatter->setTree(scatteredDensity(joint.scattered->tree(), own, BakedGrids::kScatterScale));
        if (out.scatter->activeVoxelCount() == 0) out.scatter = nullptr;
    }
    return out;
}

}  // namespace firn
