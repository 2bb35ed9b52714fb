#pragma once

// A flat slab of snow for the spray tests: its top at z = 0, uniform density, grids with a snow layer's conventions
// (surface level set negative inside, +-3 voxels of band; density zero outside, the one-voxel ramp across the top).
#include <algorithm>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>

#include "firn/snow/snow_rasterizer.h"
#include "firn/util/openvdb_library.h"

namespace firn::test {

// Slab [lo, hi] (m), voxel h (m), density (kg/m^3).
inline SnowGrids slabSnow(const openvdb::Vec3d &lo, const openvdb::Vec3d &hi, double h, float density) {
    initializeOpenVdb();
    const auto transform = openvdb::math::Transform::createLinearTransform(h);
    SnowGrids snow;
    snow.surface = openvdb::tools::createLevelSetBox<openvdb::FloatGrid>(openvdb::math::BBox<openvdb::Vec3s>(openvdb::Vec3s(lo), openvdb::Vec3s(hi)), *transform, 3.0f);
    snow.surface->setName("surface");
    snow.density = openvdb::FloatGrid::create(0.0f);
    snow.density->setName("density");
    snow.density->setTransform(transform->copy());
    snow.density->setGridClass(openvdb::GRID_FOG_VOLUME);
    const openvdb::Coord a = openvdb::Coord::floor(transform->worldToIndex(lo)) - openvdb::Coord(1);
    const openvdb::Coord b = openvdb::Coord::floor(transform->worldToIndex(hi)) + openvdb::Coord(2);
    auto phi = snow.surface->getConstAccessor();
    auto rho = snow.density->getAccessor();
    for (auto it = openvdb::CoordBBox(a, b).begin(); it; ++it) {
        const double covered = std::clamp(0.5 - phi.getValue(*it) / h, 0.0, 1.0);
        if (covered > 0.0) rho.setValue(*it, float(covered * density));
    }
    return snow;
}

// The level set at a world point (m), trilinear.
inline double levelSetAt(const openvdb::FloatGrid &grid, double x, double y, double z) {
    return openvdb::tools::BoxSampler::sample(grid.tree(), grid.worldToIndex(openvdb::Vec3d(x, y, z)));
}

}  // namespace firn::test
