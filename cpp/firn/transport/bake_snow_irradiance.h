#pragma once

// Light that surface voxels receive from other snow across the air (the gathering between snow surfaces).

#include <cstdint>

#include <glm/vec3.hpp>

#include "firn/transport/bake_grid_values.h"
#include "firn/transport/bake_source_function.h"
#include "firn/transport/bake_traced_voxels.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/progress.h"

namespace firn::bake {

// The light gathered from other snow onto the surface patches (W/m^2, per channel) and its first moment over the
// directions it arrives from (grey, as IncidentLight::skyAim).
struct SnowIrradiance {
    SurfaceValues<glm::vec3> irradiance, aim;
};

// What each surface patch receives from the snow that hides its sky rays.
SnowIrradiance snowIrradiance(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                              const SourceValues &source, const MonteCarloVoxels &traced, const GridValues &values,
                              const SkyRays &rays, std::uint64_t seed, const SubProgress &progress);

}  // namespace firn::bake
