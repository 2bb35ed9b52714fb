#pragma once

#include <cstdint>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/util/unwritten_vector.h"

namespace firn {

// The 2x2x2 blocks a level's voxels fall into (the next level of MultigridSolver's hierarchy: block floor(c / 2)),
// numbered in the order their first voxel comes in `voxels`, with each block's voxels in that order.
struct VoxelBlocks {
    UnwrittenVector<openvdb::Coord> coord;  // each block's voxel on the next level
    UnwrittenVector<std::uint32_t> ofRow;   // each voxel's block
    // Block I's voxels (rows of `voxels`): members[membersStart[I]] up to members[membersStart[I + 1]].
    std::vector<std::uint32_t> membersStart, members;
};

// The largest edge of aligned regions (8, 4 or 2 voxels) whose voxels come in one run each in `voxels`; 0 if none.
// A block lies in one region, so where the regions come whole the runs are numbered apart and in parallel: a
// leaf-ordered level (the bake's voxels, 8^3 leaves) takes 8, the level of its blocks 4.
int contiguousRegionEdge(const UnwrittenVector<openvdb::Coord> &voxels);

// The blocks of `voxels`: numbered run by run in parallel where contiguousRegionEdge finds runs, else serially;
// the same numbers either way.
VoxelBlocks voxelBlocks(const UnwrittenVector<openvdb::Coord> &voxels);

}  // namespace firn
