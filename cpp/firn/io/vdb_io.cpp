#include "firn/io/vdb_io.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "firn/io/vdb_layout.h"
#include "firn/util/error.h"
#include "firn/util/openvdb_library.h"
#include "firn/util/version.h"

namespace firn {

namespace {

const char *const kShiftKey = "firn_half_voxel_shift";  // bool file metadata: transforms shifted for Cycles

// Moves every grid by half a voxel along each axis, towards +inf (sign +1) or -inf (sign -1).
void shiftHalfVoxel(const openvdb::GridPtrVec &grids, double sign) {
    for (const openvdb::GridBase::Ptr &grid : grids) grid->transform().postTranslate(sign * 0.5 * grid->voxelSize());
}

// openvdb::io::File::write ignores stream errors, so a full disk would give a truncated file that the rename
// then puts in place of a good one. This writes the same format through a stream that fails loudly.
class CheckedFile : public openvdb::io::File {
  public:
    using openvdb::io::File::File;

    void writeChecked(const openvdb::GridCPtrVec &grids, const openvdb::MetaMap &meta) const {
        std::ofstream stream;
        stream.exceptions(std::ios_base::failbit | std::ios_base::badbit);
        errno = 0;
        try {
            stream.open(filename(), std::ios_base::out | std::ios_base::binary | std::ios_base::trunc);
            openvdb::io::Archive::write(stream, grids, /*seekable=*/true, meta);
            stream.close();
        } catch (const std::ios_base::failure &) {
            // The stream's own message says nothing; the failed system call's errno does (ENOSPC, EROFS...).
            throw std::runtime_error(errno != 0 ? std::strerror(errno) : "write failed");
        }
    }
};

// Writes `grids` as they are to a temporary file beside `path`, then renames it over `path`; on failure the
// temporary file is removed and `path` is left as it was.
void writeFileAtomically(const std::string &path, const openvdb::GridPtrVec &grids, const openvdb::MetaMap &meta) {
    const std::filesystem::path target(path);
    const std::filesystem::path temp = target.string() + ".tmp" + std::to_string(::getpid());
    try {
        if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path());
        CheckedFile(temp.string()).writeChecked(openvdb::GridCPtrVec(grids.begin(), grids.end()), meta);
        std::filesystem::rename(temp, target);
    } catch (const std::exception &e) {
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
        throw WriteError("cannot write " + path + ": " + e.what());
    }
}

}  // namespace

void writeGrids(const std::string &path, const openvdb::GridPtrVec &grids) {
    initializeOpenVdb();
    if (grids.empty()) throw InvalidArgument("no grids to write to " + path);
    openvdb::GridPtrVec copies;
    for (const openvdb::GridBase::Ptr &grid : grids) {
        openvdb::GridBase::Ptr copy = grid->deepCopyGrid();
        const bool known = copy->apply<openvdb::GridTypes>([](auto &typed) { typed.tree().voxelizeActiveTiles(); });
        if (!known) throw InvalidArgument("grid '" + grid->getName() + "' has a type Firn does not write");
        copies.push_back(copy);
    }
    shiftHalfVoxel(copies, -1.0);
    openvdb::MetaMap meta;
    meta.insertMeta(kShiftKey, openvdb::BoolMetadata(true));
    meta.insertMeta("creator", openvdb::StringMetadata(std::string("Firn ") + kVersion));
    writeFileAtomically(path, copies, meta);
}

openvdb::GridPtrVec readGrids(const std::string &path) {
    initializeOpenVdb();
    checkVdbLayout(path, VdbCheck::Trees);  // every length and offset fits the file: OpenVDB trusts them
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);  // read it all now: a truncated file fails here, not in a later reader
        openvdb::GridPtrVecPtr grids = file.getGrids();
        const openvdb::MetaMap::Ptr meta = file.getMetadata();
        file.close();
        // OpenVDB reads a file cut short inside its header as a file of no grids; Firn never writes one.
        if (grids->empty()) throw ReadError("cannot read " + path + ": no grids in it (truncated or corrupted?)");
        const auto shift = meta->getMetadata<openvdb::BoolMetadata>(kShiftKey);
        if (shift && shift->value()) shiftHalfVoxel(*grids, +1.0);
        return *grids;
    } catch (const ReadError &) {
        throw;
    } catch (const std::exception &e) {  // openvdb::Exception, and std:: ones from a corrupted or truncated file
        throw ReadError("cannot read " + path + ": " + e.what());
    }
}

openvdb::GridBase::Ptr readGrid(const std::string &path, const std::string &name) {
    initializeOpenVdb();
    checkVdbLayout(path, VdbCheck::Trees);  // as readGrids: OpenVDB trusts every length it reads
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        if (!file.hasGrid(name)) return nullptr;
        openvdb::GridPtrVec grids{file.readGrid(name)};
        const openvdb::MetaMap::Ptr meta = file.getMetadata();
        file.close();
        const auto shift = meta->getMetadata<openvdb::BoolMetadata>(kShiftKey);
        if (shift && shift->value()) shiftHalfVoxel(grids, +1.0);
        return grids.front();
    } catch (const std::exception &e) {  // openvdb::Exception, and std:: ones from a corrupted or truncated file
        throw ReadError("cannot read " + path + ": " + e.what());
    }
}

std::vector<std::string> gridNames(const std::string &path) {
    initializeOpenVdb();
    checkVdbLayout(path, VdbCheck::Header);  // a truncated file fails here
    try {
        openvdb::io::File file(path);
        file.open();  // reads the header and the grid descriptors; voxels stay on disk
        std::vector<std::string> names;
        for (auto name = file.beginName(); name != file.endName(); ++name) names.push_back(name.gridName());
        file.close();
        return names;
    } catch (const std::exception &e) {  // a damaged file throws more than openvdb::IoError
        throw ReadError("cannot read " + path + ": " + e.what());
    }
}

std::vector<std::string> removeGrids(const std::string &path, const std::vector<std::string> &names) {
    initializeOpenVdb();
    openvdb::GridPtrVec kept;
    std::vector<std::string> removed;
    openvdb::MetaMap::Ptr meta;
    checkVdbLayout(path, VdbCheck::Trees);
    try {
        // As stored (no half-voxel shift, no voxelizing): the kept grids go back exactly as they were.
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);  // everything in memory before the file is replaced
        meta = file.getMetadata();
        const openvdb::GridPtrVecPtr grids = file.getGrids();
        for (const openvdb::GridBase::Ptr &grid : *grids) {
            if (std::find(names.begin(), names.end(), grid->getName()) == names.end())
                kept.push_back(grid);
            else
                removed.push_back(grid->getName());
        }
        file.close();
    } catch (const std::exception &e) {
        throw ReadError("cannot read " + path + ": " + e.what());
    }
    if (removed.empty()) return removed;
    if (kept.empty()) throw InvalidArgument("removing those grids would leave " + path + " empty");
    writeFileAtomically(path, kept, *meta);
    return removed;
}

}  // namespace firn
