#pragma once

#include <vector>

#include <openvdb/openvdb.h>

#include "firn/transport/baked_grids.h"

namespace firn {

// Several snow objects lit as one medium: a spray's lumps and the tracked snow they fly over shade and light
// each other (the spray's shadow on the snow, the snow's light under the lumps, lumps resting in the groove).
// The baked grids hold the source function per unit extinction (docs/vdb-contract.md), so each object rendered
// with its own density and the union's source emits its own share, and where objects overlap their emissions
// and extinctions add up to the union's.

// The densities' sum (kg/m^3) on the first one's voxels; another one whose voxels differ is resampled onto them
// trilinearly. Throws InvalidArgument for no densities.
openvdb::FloatGrid::Ptr unionDensity(const std::vector<openvdb::FloatGrid::ConstPtr> &densities);

// The union's baked grids where one of its objects reads them: the source voxels whose centre lies within one
// density voxel plus one source voxel of the object's active density voxels (every voxel its trilinear density
// and source reach), with the values the union's bake gave them, and a ring of zeros around them (Cycles reads a
// grid's edge values half a voxel further). Transform and metadata as the union's. No density, empty grids. Its
// scatter grid (with the union's transform and metadata) holds the object's own scattered density over the union's
// scattered voxels (scatteredDensity of `joint.scattered` and `density`, resampled onto the union's voxels where
// they differ), and there is none where that is nowhere: the object scatters its own snow the bake traced as one
// object would, whole in the traced voxels (where the objects add up to the union) and beside them at most its own
// traced density. The union's scattered density over the object's own (before stop 96) scattered, where objects
// overlap beside thin snow, up to each one's share of it on top of the others'. Throws InvalidArgument for a
// scatter grid without its scattered voxels.
BakedGrids bakedGridsOf(const BakedGrids &joint, const openvdb::FloatGrid &density);

}  // namespace firn
