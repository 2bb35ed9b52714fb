#pragma once

#include <cstddef>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/snow/compaction.h"
#include "firn/snow/metaball_layout.h"
#include "firn/util/progress.h"

namespace firn {

// The snow's grids in world space (contract: docs/vdb-contract.md).
struct SnowGrids {
    openvdb::FloatGrid::Ptr density;  // kg/m^3, zero outside the snow
    openvdb::FloatGrid::Ptr surface;  // level set: signed distance to the snow surface (m), negative inside
};

struct RasterSettings {
    double voxelSize = 0.01;     // m
    double maxVoxels = 50e6;     // active voxels allowed before allocating
    CompactionProfile compaction;
};

// Active voxels the balls will need, estimated cheaply before anything is allocated.
double estimateVoxelCount(const std::vector<Metaball> &balls, double spacing, double voxelSize);

// Throws BudgetExceeded, with the voxel size that would fit, when `voxels` exceeds settings.maxVoxels; the
// message says the snow needs `quantifier` (about, at least) that many.
void checkVoxelBudget(double voxels, const RasterSettings &settings, const char *quantifier = "about");

// Sums the balls' fields on a sparse grid in one parallel, deterministic pass (each 8^3 leaf gathers the
// balls that reach it). Snow is where the field exceeds the iso-value and which lies above the surface the
// balls stand on; the level set is its signed distance, the density follows compaction by depth below the
// top, antialiased over one voxel at the surface. Throws BudgetExceeded, before allocating, when the leaves
// would hold more than maxVoxels.
SnowGrids rasterizeSnow(const std::vector<Metaball> &balls, const RasterSettings &settings,
                        const SubProgress &progress);

}  // namespace firn
