#include "firn/io/vdb_io.h"

#include <filesystem>

#include <unistd.h>

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

    const std::filesystem::path target(path);
    const std::filesystem::path temp = target.string() + ".tmp" + std::to_string(::getpid());
    try {
        if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path());
        openvdb::io::File file(temp.string());
        openvdb::MetaMap meta;
        meta.insertMeta(kShiftKey, openvdb::BoolMetadata(true));
        meta.insertMeta("creator", openvdb::StringMetadata(std::string("Firn ") + kVersion));
        file.write(copies, meta);
        file.close();
        std::filesystem::rename(temp, target);
    } catch (const std::exception &e) {
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
        throw IoError("cannot write " + path + ": " + e.what());
    }
}

openvdb::GridPtrVec readGrids(const std::string &path) {
    initializeOpenVdb();
    try {
        openvdb::io::File file(path);
        file.open();
        openvdb::GridPtrVecPtr grids = file.getGrids();
        const openvdb::MetaMap::Ptr meta = file.getMetadata();
        file.close();
        // OpenVDB reads a file cut short inside its header as a file of no grids; Firn never writes one.
        if (grids->empty()) throw IoError("cannot read " + path + ": no grids in it (truncated or corrupted?)");
        const auto shift = meta->getMetadata<openvdb::BoolMetadata>(kShiftKey);
        if (shift && shift->value()) shiftHalfVoxel(*grids, +1.0);
        return *grids;
    } catch (const IoError &) {
        throw;
    } catch (const std::exception &e) {  // openvdb::Exception, and std:: ones from a corrupted or truncated file
        throw IoError("cannot read " + path + ": " + e.what());
    }
}

}  // namespace firn
