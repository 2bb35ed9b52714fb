#pragma once

// The empty density grid the core's tests fill: named "density" as Firn's files name it, of cubic voxels.
#include <openvdb/openvdb.h>

#include "firn/util/openvdb_library.h"

namespace firn::test {

// An empty density grid (background 0 kg/m^3) of `voxel` m voxels, OpenVDB initialised.
inline openvdb::FloatGrid::Ptr densityGrid(double voxel) {
    initializeOpenVdb();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    return grid;
}

}  // namespace firn::test
