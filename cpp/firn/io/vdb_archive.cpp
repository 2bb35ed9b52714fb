#include "firn/io/vdb_archive.h"

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <openvdb/io/Archive.h>
#include <openvdb/io/Compression.h>
#include <openvdb/io/DelayedLoadMetadata.h>
#include <openvdb/io/GridDescriptor.h>
#include <tbb/parallel_for.h>

#include "firn/util/error.h"

namespace firn {

namespace {

namespace io = openvdb::io;

// The grid types OpenVDB 10 gives a delayed-load table (io/Archive.cc, populateDelayedLoadMetadata).
using DelayedLoadGridTypes = openvdb::TypeList<openvdb::Int32Grid, openvdb::Int64Grid, openvdb::FloatGrid,
                                               openvdb::DoubleGrid, openvdb::Vec3IGrid, openvdb::Vec3SGrid,
                                               openvdb::Vec3DGrid>;

// A grid's leaf buffers, compressed ahead of the write with the stream's settings for that grid.
class CompressedLeaves {
  public:
    virtual ~CompressedLeaves() = default;
    // Compresses every leaf as its writeBuffers would write it to `settings` (compression, half floats) on all
    // cores; `archiveCompression` is the file's flags, which size the delayed-load table. Checks `progress` for
    // cancellation per chunk of leaves.
    virtual void compress(std::ostream &settings, std::uint32_t archiveCompression, const Progress *progress) = 0;
    // The delayed-load table OpenVDB would write for the grid, or null for a type it writes none for.
    virtual io::DelayedLoadMetadata::Ptr delayedLoad() const = 0;
};

// Bytes a leaf writes ahead of its values' compressed block (LeafNode::writeBuffers, io::writeCompressedValues):
// its value mask, the mask-compression byte, the inactive values kept and the mask that selects between two.
template <typename Leaf>
std::size_t headerBytes(std::int8_t written) {
    using Mask = typename Leaf::NodeMaskType;
    const int inactiveValues = written == io::NO_MASK_AND_ONE_INACTIVE_VAL || written == io::MASK_AND_ONE_INACTIVE_VAL
                                   ? 1
                                   : (written == io::MASK_AND_TWO_INACTIVE_VALS ? 2 : 0);
    const bool selection = written == io::MASK_AND_NO_INACTIVE_VALS || written == io::MASK_AND_ONE_INACTIVE_VAL ||
                           written == io::MASK_AND_TWO_INACTIVE_VALS;
    return Mask::memUsage() + 1 + inactiveValues * sizeof(typename Leaf::ValueType) +
           (selection ? Mask::memUsage() : 0);
}

// A grid sharing `grid`'s tree (its own transform and metadata) whose leaf buffers are written as OpenVDB writes
// them, in the same order and bytes, from chunks compressed on every core before the write.
template <typename GridT>
class PrecompressedGrid : public GridT, public CompressedLeaves {
  public:
    explicit PrecompressedGrid(GridT &grid) : GridT(grid, openvdb::ShallowCopy()) {}

    void compress(std::ostream &settings, std::uint32_t archiveCompression, const Progress *progress) override {
        using Leaf = typename GridT::TreeType::LeafNodeType;
        constexpr bool kTable = DelayedLoadGridTypes::Contains<GridT>;
        if constexpr (kTable) delayedLoad_ = std::make_shared<io::DelayedLoadMetadata>();
        if (GridT::hasMultiPassIO()) return;  // points: passes over the leaves, written by OpenVDB itself
        std::vector<const Leaf *> leaves;
        this->tree().getNodes(leaves);  // the order Tree::writeBuffers visits them
        const auto &background = this->tree().background();
        const bool maskCompressed = io::getDataCompression(settings) & io::COMPRESS_ACTIVE_MASK;
        const bool sized = archiveCompression & (io::COMPRESS_BLOSC | io::COMPRESS_ZIP);
        if constexpr (kTable) {
            if (!leaves.empty()) delayedLoad_->resizeMask(leaves.size());
            if (!leaves.empty() && sized) delayedLoad_->resizeCompressedSize(leaves.size());
        }
        // Set once here, not in each task: it also writes the grid's StreamMetadata, which every chunk shares
        // through copyfmt (the topology's write, which comes later, sets it again).
        io::setGridBackgroundValuePtr(settings, &background);
        constexpr std::size_t kLeavesPerChunk = 64;
        chunks_.assign((leaves.size() + kLeavesPerChunk - 1) / kLeavesPerChunk, std::string());
        tbb::parallel_for(std::size_t(0), chunks_.size(), [&](std::size_t c) {
            if (progress) progress->throwIfCancelled();  // a chunk: 64 leaves, at most 32768 values
            std::ostringstream chunk;
            chunk.copyfmt(settings);  // OpenVDB's per-stream settings: compression, half floats, background
            const std::size_t first = c * kLeavesPerChunk, end = std::min(leaves.size(), first + kLeavesPerChunk);
            std::array<std::size_t, kLeavesPerChunk + 1> starts{};  // each leaf's bytes in the chunk
            for (std::size_t l = first; l < end; ++l) {
                starts[l - first] = std::size_t(chunk.tellp());
                leaves[l]->writeBuffers(chunk, this->saveFloatAsHalf());
            }
            starts[end - first] = std::size_t(chunk.tellp());
            chunks_[c] = std::move(chunk).str();
            if constexpr (kTable) {
                using Mask = typename Leaf::NodeMaskType;
                for (std::size_t l = first; l < end; ++l) {
                    // As populateDelayedLoadMetadata: the mask compression found whether or not the file uses it
                    // (when it does, the byte the leaf wrote after its value mask), and the size of the
                    // compressed block with its 8-byte length.
                    const std::size_t at = starts[l - first];
                    const std::int8_t kind =
                        maskCompressed
                            ? std::int8_t(chunks_[c][at + Mask::memUsage()])
                            : io::MaskCompress<typename Leaf::ValueType, Mask>(leaves[l]->valueMask(), Mask(),
                                                                               leaves[l]->buffer().data(), background)
                                  .metadata;
                    delayedLoad_->setMask(l, kind);
                    const std::int8_t written = maskCompressed ? kind : std::int8_t(io::NO_MASK_AND_ALL_VALS);
                    if (sized)
                        delayedLoad_->setCompressedSize(l, starts[l - first + 1] - at - headerBytes<Leaf>(written));
                }
            }
        });
    }

    io::DelayedLoadMetadata::Ptr delayedLoad() const override { return delayedLoad_; }

    void writeBuffers(std::ostream &os) const override {
        if (GridT::hasMultiPassIO()) return GridT::writeBuffers(os);
        for (const std::string &chunk : chunks_) os.write(chunk.data(), std::streamsize(chunk.size()));
    }

  private:
    std::vector<std::string> chunks_;
    io::DelayedLoadMetadata::Ptr delayedLoad_;
};

struct Precompressed {
    openvdb::GridBase::Ptr grid;
    CompressedLeaves *leaves;
};

Precompressed precompressed(const openvdb::GridBase::Ptr &grid) {
    Precompressed out{};
    const bool known = grid->apply<openvdb::GridTypes>([&](auto &typed) {
        using GridT = std::decay_t<decltype(typed)>;
        auto wrapped = std::make_shared<PrecompressedGrid<GridT>>(typed);
        out = {wrapped, wrapped.get()};
    });
    if (!known) throw InvalidArgument("grid '" + grid->getName() + "' has a type Firn does not write");
    return out;
}

// openvdb::io::Archive's write, with its writeGrid taking the delayed-load table from the grid's own compression
// (OpenVDB 10.0, io/Archive.cc: the same steps in the same order, so the same bytes).
class ArchiveWriter : public io::Archive {
  public:
    void write(std::ostream &os, const std::vector<Precompressed> &grids, const openvdb::MetaMap &meta,
               const Progress *progress) const {
        io::StreamMetadata::Ptr fileSettings = io::getStreamMetadataPtr(os);
        if (!fileSettings) {
            fileSettings = std::make_shared<io::StreamMetadata>();
            io::setStreamMetadataPtr(os, fileSettings, /*transfer=*/false);
        }
        io::setDataCompression(os, compression());
        io::setWriteGridStatsMetadata(os, isGridStatsMetadataEnabled());
        writeHeader(os, /*seekable=*/true);
        meta.writeMeta(os);
        const auto count = std::int32_t(grids.size());
        os.write(reinterpret_cast<const char *>(&count), sizeof(count));

        std::map<std::string, int> nameCount;
        for (const Precompressed &g : grids) ++nameCount[g.grid->getName()];
        std::set<std::string> uniqueNames;
        std::map<const openvdb::TreeBase *, io::GridDescriptor> written;  // trees already in the file
        for (const Precompressed &g : grids) {
            if (progress) progress->throwIfCancelled();  // the grid before written out
            const openvdb::GridBase &grid = *g.grid;
            std::string name = grid.getName();
            if (name.empty() || nameCount[name] > 1) name = io::GridDescriptor::addSuffix(name, 0);
            for (int n = 1; uniqueNames.count(name); ++n) name = io::GridDescriptor::addSuffix(grid.getName(), n);
            uniqueNames.insert(name);
            io::GridDescriptor gd(name, grid.type(), grid.saveFloatAsHalf());
            const auto same = written.find(&grid.baseTree());
            if (isInstancingEnabled() && same != written.end() &&
                same->second.saveFloatAsHalf() == gd.saveFloatAsHalf()) {
                gd.setInstanceParentName(same->second.uniqueName());
                writeGridInstance(gd, g.grid, os, /*seekable=*/true);
            } else {
                writeGrid(gd, g, os, fileSettings, progress);
                written[&grid.baseTree()] = gd;
            }
            io::setDataCompression(os, compression());  // mask compression is set per grid
        }
    }

  private:
    void writeGrid(io::GridDescriptor &gd, const Precompressed &g, std::ostream &os,
                   io::StreamMetadata::Ptr &fileSettings, const Progress *progress) const {
        const openvdb::GridBase &grid = *g.grid;
        // Per-grid stream settings, the file's back on the way out.
        io::StreamMetadata::Ptr gridSettings = std::make_shared<io::StreamMetadata>(*fileSettings);
        gridSettings->setHalfFloat(grid.saveFloatAsHalf());
        gridSettings->gridMetadata() = static_cast<const openvdb::MetaMap &>(grid);
        io::setStreamMetadataPtr(os, gridSettings, /*transfer=*/false);
        struct Restore {
            std::ostream &os;
            io::StreamMetadata::Ptr &settings;
            ~Restore() { io::setStreamMetadataPtr(os, settings, /*transfer=*/false); }
        } restore{os, fileSettings};

        gd.writeHeader(os);
        const std::int64_t offsetPos = os.tellp();
        gd.writeStreamPos(os);  // a placeholder, rewritten at the end
        gd.setGridPos(os.tellp());
        setGridCompression(os, grid);
        g.leaves->compress(os, compression(), progress);

        const openvdb::GridBase::Ptr copy = g.grid->copyGrid();  // shallow: the file's metadata added to it
        if (const io::DelayedLoadMetadata::Ptr table = g.leaves->delayedLoad())
            copy->insertMeta(openvdb::GridBase::META_FILE_DELAYED_LOAD, *table);
        else
            copy->removeMeta(openvdb::GridBase::META_FILE_DELAYED_LOAD);
        if (io::getWriteGridStatsMetadata(os)) {
            copy->addStatsMetadata();
            copy->insertMeta(openvdb::GridBase::META_FILE_COMPRESSION,
                             openvdb::StringMetadata(io::compressionToString(io::getDataCompression(os))));
        }
        copy->writeMeta(os);
        grid.writeTransform(os);
        grid.writeTopology(os);
        gd.setBlockPos(os.tellp());
        grid.writeBuffers(os);
        gd.setEndPos(os.tellp());
        os.seekp(offsetPos, std::ios_base::beg);
        gd.writeStreamPos(os);
        gd.seekToEnd(os);
    }
};

}  // namespace

void writeVdbArchive(std::ostream &stream, const openvdb::GridPtrVec &grids, const openvdb::MetaMap &meta,
                     const Progress *progress) {
    std::vector<Precompressed> wrapped;
    for (const openvdb::GridBase::Ptr &grid : grids)
        if (grid) wrapped.push_back(precompressed(grid));
    ArchiveWriter().write(stream, wrapped, meta, progress);
}

}  // namespace firn
