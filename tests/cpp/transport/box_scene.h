#pragma once

// A box of uniform snow under one sun, the scene the traced-voxel tests bake: the density grid's voxels of h = 1 cm.
#include <memory>

#include <glm/geometric.hpp>

#include "density_grid.h"
#include "firn/transport/scene.h"

namespace firn::test {

constexpr double kBoxVoxel = 0.01;  // m

// Voxels [lo, hi] of `density` (kg/m^3) with `optics`, lit by a sun from `toSun` (normalised here).
inline Scene boxScene(const openvdb::CoordBBox &voxels, float density, const VolumeOptics &optics,
                      const glm::dvec3 &toSun) {
    auto grid = densityGrid(kBoxVoxel);
    grid->fill(voxels, density);
    Scene scene;
    scene.medium = std::make_shared<Medium>(grid, optics);
    scene.suns = {SunLight{glm::normalize(toSun), Rgb(1.0), 0.0093}};
    return scene;
}

}  // namespace firn::test
