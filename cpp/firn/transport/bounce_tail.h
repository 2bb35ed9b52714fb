#pragma once

#include <glm/glm.hpp>

#include "firn/transport/snow_topology.h"

namespace firn {

// Light between snow surfaces beyond the bounces gathered, added to the last gather `last` (W/m^2 per surface
// patch, all bounces so far; `before`, `older`: the two gathers before it, none: zero). Each bounce returns
// about the same share r of the one before, measured per channel from the last two bounces over the patches of
// a region (area-weighted; a block of 2^kBounceRegionLog2 voxels a side), so the rest of the geometric series is
// each patch's last bounce times r / (1 - r), r at most kMaxBounceShare. A patch's last bounce is light added,
// never taken: where the fits of two passes make it negative it adds nothing (scaled by up to 4, it would make
// the patch's light negative).
// Per region, not over all patches: a dense cluster's light returns a larger share each bounce than a lone
// piece's, and r / (1 - r) grows faster than r, so one ratio over all of them gives the dense parts too short a
// tail. The skier sample's 9,334 lumps, 176,775 voxels (bench/skier_light_bench.py, sun and sky): the shares of
// successive bounces over all patches 0.56, 0.62, 0.66, 0.68, 0.70, 0.72, 0.73 (the dense parts' light outlasts
// the rest); after two gathers the tail with one ratio over all patches held 10.8 of the 16.6 W/m^2 (area-
// weighted sum, green) that nine gathers and their own tail find, per block of 8 voxels 15.9.
// For a cloud of small pieces left to the diffusion they light each other over many bounces (those lumps alone,
// sun only, against the core's Monte Carlo: -39 % without the gathering, -17 % with one bounce, +5 % with four).
constexpr int kBounceRegionLog2 = 3;
constexpr double kMaxBounceShare = 0.8;
void addBounceTail(const SnowTopology &topo, const SurfaceValues<glm::vec3> *older, const SurfaceValues<glm::vec3> &before,
                   SurfaceValues<glm::vec3> &last);

}  // namespace firn
