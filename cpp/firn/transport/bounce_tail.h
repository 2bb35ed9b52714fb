#pragma once

#include <glm/glm.hpp>

#include "firn/transport/snow_topology.h"

namespace firn {

// Light between snow surfaces beyond the bounces gathered, added to the last gather `last` (W/m^2 per surface
// patch, all bounces so far; `before`, `older`: the two gathers before it, none: zero). Each bounce returns
// about the same share r of the one before, measured per channel from the last two bounces over all patches
// (area-weighted), so the rest of the geometric series is each patch's last bounce times r / (1 - r), r at most
// kMaxBounceShare. A patch's last bounce is light added, never taken: where the fits of two passes make it
// negative it adds nothing (scaled by up to 4, it would make the patch's light negative).
// For a cloud of small pieces left to the diffusion (the skier sample's 9,334 lumps, 176,775 voxels): they light
// each other over many bounces (those lumps alone, sun only, against the core's Monte Carlo: -39 % without the
// gathering, -17 % with one bounce, +5 % with four, +10 % with two and this tail; r about 0.5; the whole frame,
// sun and sky over the snow, -33 % -> -14 %; bench/skier_light_bench.py).
constexpr double kMaxBounceShare = 0.8;
void addBounceTail(const SnowTopology &topo, const SurfaceValues<glm::vec3> *older, const SurfaceValues<glm::vec3> &before,
                   SurfaceValues<glm::vec3> &last);

}  // namespace firn
