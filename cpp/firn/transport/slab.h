#pragma once

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/transport/baked_grids.h"
#include "firn/transport/medium.h"

namespace firn {

// Test geometry for the plane-parallel oracles: a box of uniform density (kg/m^3), `width` x `width`
// voxels centred on the z axis and `layers` voxels deep, voxel centres at z = -h/2, -3h/2, ... so the
// trilinear density's top surface (its half-column point) lies at z = 0.
openvdb::FloatGrid::Ptr makeSlabDensity(double voxelSize, int width, int layers, float density);

// Radiance flux (W/m^2) leaving a surface point through the hemisphere around `normal`, from the
// rendered baked radiance (renderBaked) on camera rays aimed at the point: Gauss-Legendre in cos(zenith),
// uniform in azimuth.
double renderedExitance(const Scene &scene, const BakedGrids &baked, const glm::dvec3 &point,
                        const glm::dvec3 &normal, int channel, int muNodes = 8, int phiNodes = 8);

}  // namespace firn
