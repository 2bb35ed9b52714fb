#pragma once

#include <string>

#include <openvdb/openvdb.h>

namespace firn {

// Reads and writes Firn's VDB files, the seam with the add-on (the contract is docs/vdb-contract.md).
//
// In memory, a grid's transform is OpenVDB's: voxel (i, j, k) is centred at its index-to-world position.
// Cycles draws voxel i centred half a voxel further along every axis, so the file's transform is
// shifted by -h/2; readGrids shifts it back. The file says so in its metadata.

// Writes to a temporary file beside `path`, then renames it over `path`: a reader never sees half a file.
// Active tiles are voxelized first (Cycles renders tiles as empty).
void writeGrids(const std::string &path, const openvdb::GridPtrVec &grids);

// Every grid in the file, with in-memory (unshifted) transforms. Throws IoError, also for a file without grids
// and for any exception OpenVDB's reader raises on a corrupted file.
openvdb::GridPtrVec readGrids(const std::string &path);

}  // namespace firn
