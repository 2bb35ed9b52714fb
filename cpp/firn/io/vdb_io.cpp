#include "firn/io/vdb_io.h"

#include <algorithm>
#include <memory>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <tbb/parallel_for.h>

#include "firn/io/atomic_file.h"
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

// A grid sharing `grid`'s tree whose leaf buffers are written as OpenVDB writes them, in the same order and bytes,
// but compressed on every core first: OpenVDB compresses leaf after leaf on one (a serial 0.05 s per grid of
// 1.8 M voxels with Blosc), which held the snow's write back while the other core waited.
template <typename GridT>
class ParallelBuffersGrid : public GridT {
  public:
    explicit ParallelBuffersGrid(GridT &grid) : GridT(grid, openvdb::ShallowCopy()) {}

    void writeBuffers(std::ostream &os) const override {
        if (GridT::hasMultiPassIO()) return GridT::writeBuffers(os);  // points: passes over the leaves
        using Leaf = typename GridT::TreeType::LeafNodeType;
        std::vector<const Leaf *> leaves;
        this->tree().getNodes(leaves);  // the order Tree::writeBuffers visits them
        constexpr std::size_t kLeavesPerChunk = 64;
        std::vector<std::string> chunks((leaves.size() + kLeavesPerChunk - 1) / kLeavesPerChunk);
        tbb::parallel_for(std::size_t(0), chunks.size(), [&](std::size_t c) {
            std::ostringstream chunk;
            chunk.copyfmt(os);  // OpenVDB's per-stream settings: compression, background, half floats
            const std::size_t end = std::min(leaves.size(), (c + 1) * kLeavesPerChunk);
            for (std::size_t l = c * kLeavesPerChunk; l < end; ++l)
                leaves[l]->writeBuffers(chunk, this->saveFloatAsHalf());
            chunks[c] = std::move(chunk).str();
        });
        for (const std::string &chunk : chunks) os.write(chunk.data(), std::streamsize(chunk.size()));
    }
};

// openvdb::io::File::write ignores stream errors, so a full disk would give a truncated file that the rename
// then puts in place of a good one. This writes the same format through writeFileAtomically's checked stream.
class ArchiveWriter : public openvdb::io::Archive {
  public:
    void writeTo(std::ostream &stream, const openvdb::GridPtrVec &grids, const openvdb::MetaMap &meta) const {
        openvdb::io::Archive::write(stream, openvdb::GridCPtrVec(grids.begin(), grids.end()), /*seekable=*/true,
                                    meta);
    }
};

void writeVdbAtomically(const std::string &path, const openvdb::GridPtrVec &grids, const openvdb::MetaMap &meta) {
    writeFileAtomically(path, [&](std::ostream &stream) { ArchiveWriter().writeTo(stream, grids, meta); });
}

}  // namespace

void writeGrids(const std::string &path, const openvdb::GridPtrVec &grids) {
    initializeOpenVdb();
    if (grids.empty()) throw InvalidArgument("no grids to write to " + path);
    // Copies whose transforms are shifted; their trees are shared with the grids' unless active tiles must be made
    // voxels (a bake's six source grids copied deep took 185 bytes per voxel more while the slab's file was written).
    openvdb::GridPtrVec copies;
    for (const openvdb::GridBase::Ptr &grid : grids) {
        openvdb::GridBase::Ptr copy;
        const bool known = grid->apply<openvdb::GridTypes>([&](auto &typed) {
            using GridT = std::decay_t<decltype(typed)>;
            if (typed.tree().hasActiveTiles()) {
                auto deep = typed.deepCopy();
                deep->tree().voxelizeActiveTiles();
                copy = std::make_shared<ParallelBuffersGrid<GridT>>(*deep);
            } else {
                copy = std::make_shared<ParallelBuffersGrid<GridT>>(typed);  // its own transform, the tree shared
            }
        });
        if (!known) throw InvalidArgument("grid '" + grid->getName() + "' has a type Firn does not write");
        copies.push_back(copy);
    }
    shiftHalfVoxel(copies, -1.0);
    openvdb::MetaMap meta;
    meta.insertMeta(kShiftKey, openvdb::BoolMetadata(true));
    meta.insertMeta("creator", openvdb::StringMetadata(std::string("Firn ") + kVersion));
    writeVdbAtomically(path, copies, meta);
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
