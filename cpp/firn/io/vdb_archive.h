#pragma once

#include <ostream>

#include <openvdb/openvdb.h>

#include "firn/util/progress.h"

namespace firn {

// Writes `grids` (any of openvdb::GridTypes) and the file's `meta` to `stream` in OpenVDB's seekable file format,
// the bytes openvdb::io::File::write gives (but the file's random UUID), with every leaf compressed once, on all
// cores: OpenVDB 10 compresses the leaves one after the other, and each once more, first, to size its delayed-load
// table ("file_delayed_load"); here that table comes from the same compression. Throws InvalidArgument for a grid
// of another type; stream errors are the stream's (its exceptions mask). Throws firn::Cancelled, part of the file
// written, when `progress` is cancelled (checked per chunk of leaves compressed): write to a file to be discarded.
void writeVdbArchive(std::ostream &stream, const openvdb::GridPtrVec &grids, const openvdb::MetaMap &meta,
                     const Progress *progress = nullptr);

}  // namespace firn
