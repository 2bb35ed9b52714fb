#include "firn/io/vdb_io.h"

#include <algorithm>
#include <string>
#include <vector>

#include "firn/io/atomic_file.h"
#include "firn/io/vdb_archive.h"
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

// Through writeFileAtomically's checked stream: openvdb::io::File::write ignores stream errors, so a full disk
// would give a truncated file that the rename then puts in place of a good one.
void writeVdbAtomically(const std::string &path, const openvdb::GridPtrVec &grids, const openvdb::MetaMap &meta,
                        const Progress *progress = nullptr) {
    writeFileAtomically(path, [&](std::ostream &stream) { writeVdbArchive(stream, grids, meta, progress); });
}

}  // namespace

void writeGrids(const std::string &path, const openvdb::GridPtrVec &grids, const Progress *progress) {
    initializeOpenVdb();
    if (grids.empty()) throw InvalidArgument("no grids to write to " + path);
    // Copies whose transforms are shifted; their trees are shared with the grids' unless active tiles must be made
    // voxels (a bake's six source grids copied deep took 185 bytes per voxel more while the slab's file was written).
    openvdb::GridPtrVec copies;
    for (const openvdb::GridBase::Ptr &grid : grids) {
        openvdb::GridBase::Ptr copy;
        const bool known = grid->apply<openvdb::GridTypes>([&](auto &typed) {
            if (typed.tree().hasActiveTiles()) {
                auto deep = typed.deepCopy();
                deep->tree().voxelizeActiveTiles();
                copy = deep;
            } else {
                copy = typed.copyGrid();  // its own transform, the tree shared
            }
        });
        if (!known) throw InvalidArgument("grid '" + grid->getName() + "' has a type Firn does not write");
        copies.push_back(copy);
    }
    shiftHalfVoxel(copies, -1.0);
    openvdb::MetaMap meta;
    meta.insertMeta(kShiftKey, openvdb::BoolMetadata(true));
    meta.insertMeta("creator", openvdb::StringMetadata(std::string("Firn ") + kVersion));
    writeVdbAtomically(path, copies, meta, progress);
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
    writeVdbAtomically(path, kept, *meta);
    return removed;
}

}  // namespace firn
