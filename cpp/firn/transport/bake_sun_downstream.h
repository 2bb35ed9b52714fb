#pragma once

// Where the suns' light a half-space returns leaves: downstream of where it entered.

#include <array>
#include <cstddef>

#include <glm/vec3.hpp>

#include "firn/transport/bake_diffusion_system.h"
#include "firn/transport/bake_surface_light.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"

namespace firn::bake {

// The suns' light the half-space model returns at the smooth patch it entered, which leaves downstream
// (sunLeavingDownstream, by the half-space's displacement `downstream` +- `spread`, m), one channel's: what the
// diffusion misses of it and its share of the sun lobe's shape (W and moments), and what escaped at once (W).
// Held for the three channels while surfaceLight works out their surfaces, after the pass's solves (in SurfaceLight,
// through all three solves, it put the car's peak at 311-313 bytes per active voxel; docs/bake.md, Memory).
struct SunReturned {
    float l0 = 0.0f;
    glm::vec3 l1{0.0f};
    float atOnce = 0.0f;
    glm::vec3 downstream{0.0f};
    float spread = 0.0f;
};

// Surface voxel i's downstream kernel (`surface`'s downstream and spread) from the beams entering it.
void downstreamKernel(const Scene &scene, const IncidentLight &light, const SurfaceTerms &sys, const Channel &ch,
                      const SnowTopology &topo, std::size_t i, SunReturned &surface);

// The three channels' sun light each smooth patch returns at once, moved to where it leaves (added to `out`).
void sunLeavingDownstream(const SnowTopology &topo, const std::array<SurfaceValues<SunReturned>, 3> &sun, double h,
                          SurfaceValues<SurfaceLight> &out, const SubProgress &progress);

}  // namespace firn::bake
