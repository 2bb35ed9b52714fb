#pragma once

#include "firn/snow/snow_rasterizer.h"
#include "firn/spray/particles.h"

namespace firn {

// The lumps' metaballs as grids with a snow layer's contract (docs/vdb-contract.md): `density` (kg/m^3: the lump
// density inside the balls' iso-surface, the snow layer's one-voxel ramp across it) and `surface` (level set, m).
// Rasterized by the snow layer's rasterizer (snow/snow_rasterizer.h), with uniform density and no ground under the
// balls. Throws BudgetExceeded, before allocating, over settings.maxVoxels.
SnowGrids rasterizeSpray(const SprayParticles &particles, double lumpDensity, const RasterSettings &settings,
                         const SubProgress &progress);

}  // namespace firn
