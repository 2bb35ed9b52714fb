#pragma once

#include "firn/geometry/mesh.h"
#include "firn/geometry/ray_caster.h"
#include "firn/snow/snowfall.h"

namespace firn {

// A lower bound on the active voxels of a snow layer (voxel size h, `depth` m of snow on open level ground),
// computed before any landing site is placed, in milliseconds whatever the scene's size: the snow's own volume
// over h^3. The volume is the depth times the targets' area weighted by slope cover, times the fraction of
// that area open to the snowfall, estimated from `samples` seeded rays into the snowfall cone against
// `shelter` and taken at its lower 3-sigma bound. Every voxel inside the snow is active, and the metaballs'
// reach and the surface's band only add to it (planes need about 3 times the bound), so a bound over the
// budget is a sure refusal, minutes earlier than the count of the placed balls.
double snowVoxelLowerBound(const TriangleMesh &targets, const RayCaster &shelter, const SnowfallSettings &snowfall,
                           double depth, double voxelSize, int samples = 1024);

}  // namespace firn
