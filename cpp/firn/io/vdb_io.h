#pragma once

#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/util/progress.h"

namespace firn {

// Reads and writes Firn's VDB files, the seam with the add-on (the contract is docs/vdb-contract.md).
//
// In memory, a grid's transform is OpenVDB's: voxel (i, j, k) is centred at its index-to-world position.
// Cycles draws voxel i centred half a voxel further along every axis, so the file's transform is
// shifted by -h/2; readGrids shifts it back. The file says so in its metadata.

// Writes to a temporary file beside `path`, then renames it over `path`: a reader never sees half a file.
// Active tiles are voxelized first (Cycles renders tiles as empty). Throws firn::Cancelled, `path` left as it was,
// when `progress` is cancelled while the grids are compressed.
void writeGrids(const std::string &path, const openvdb::GridPtrVec &grids, const Progress *progress = nullptr);

// Every grid in the file, read in full, with in-memory (unshifted) transforms. Throws IoError, also for a
// damaged (truncated, corrupted) file, a file without grids, and any exception OpenVDB's reader raises.
openvdb::GridPtrVec readGrids(const std::string &path);

// The grid called `name` alone, read in full, with its in-memory transform; nullptr when the file has none of
// that name. Throws ReadError as readGrids does.
openvdb::GridBase::Ptr readGrid(const std::string &path, const std::string &name);

// The names of the file's grids, from its header alone (no voxel is read). Throws IoError.
std::vector<std::string> gridNames(const std::string &path);

// Rewrites the file at `path` without the grids named in `names`, atomically as writeGrids does; the other
// grids, their transforms and the file's metadata are written back unchanged. Returns the names removed; when
// none is in the file, the file is left untouched. Throws IoError, InvalidArgument if no grid would remain.
std::vector<std::string> removeGrids(const std::string &path, const std::vector<std::string> &names);

}  // namespace firn
