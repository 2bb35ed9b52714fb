#pragma once

// Which voxels of the snow are traced by Monte Carlo rather than diffused.

#include <cstddef>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/snow_topology.h"

namespace firn::bake {

// The voxels traced rather than diffused: `thin`, and the other voxels of transport-thin pieces (`wholePieces`:
// traced too where light tracing takes them, bakeScattering; `inLayer`, per voxel of `thin` then `wholePieces`, the
// order the bake traces them whole in: its piece is a layer, traced whole for having no inside; never a thin one).
struct TracedSnow {
    std::vector<openvdb::Coord> thin, wholePieces;
    std::vector<bool> inLayer;

    std::vector<openvdb::Coord> voxels() const;  // thin, then wholePieces
};

// The thin voxels and transport-thin pieces of the medium's snow (bake_thin_snow.cpp: what each is, measured).
TracedSnow thinVoxels(const Medium &medium, const SnowTopology &topo);

// The traced voxels the renderer scatters itself (firn_scatter, docs/vdb-contract.md): snow.voxels(), less the thin
// voxels beside snow the diffusion keeps where the snow absorbs (bake_thin_snow.cpp, kFringeScatterAbsorption).
std::vector<openvdb::Coord> scatteredVoxels(const Medium &medium, const TracedSnow &snow);

}  // namespace firn::bake
