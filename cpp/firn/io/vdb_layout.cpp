#include "firn/io/vdb_layout.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <map>
#include <set>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "firn/util/error.h"

namespace firn {

namespace {

// The format as OpenVDB 10 writes and reads it (io/Archive.cc, io/GridDescriptor.cc, MetaMap.cc).
constexpr std::int64_t kMagic = 0x56444220;             // "VDB "
constexpr std::uint32_t kFirstWalkedVersion = 222;      // per-grid compression flags; OpenVDB 3.0 on
constexpr std::uint64_t kHeaderBytes = 8 + 4 + 4 + 4 + 1 + 36;  // magic, versions, offsets flag, UUID
constexpr std::uint64_t kBloscPadBytes = 128;         // points/StreamCompression.h BLOSC_PAD_BYTES
constexpr std::uint64_t kMinLeafBytes = 2 * 64;         // a leaf's value mask in the topology and again before its values

// Reads little-endian values and length-prefixed strings from a range of the file, refusing any length or
// offset beyond the range's end: a corrupted field fails here, before OpenVDB allocates what it says.
class Cursor {
  public:
    Cursor(const char *file, std::uint64_t position, std::uint64_t end) : file_(file), position_(position), end_(end) {}

    // The next `bytes` bytes, as a cursor of their own.
    Cursor range(std::uint64_t bytes) const {
        need(bytes, "value");
        return Cursor(file_, position_, position_ + bytes);
    }

    std::uint64_t position() const { return position_; }
    std::uint64_t remaining() const { return end_ - position_; }

    void need(std::uint64_t bytes, const char *what) const {
        if (bytes > remaining())
            throw ReadError(std::string(what) + " of " + std::to_string(bytes) + " bytes where " +
                            std::to_string(remaining()) + " remain (truncated or corrupted)");
    }

    template <typename T>
    T value(const char *what) {
        need(sizeof(T), what);
        T v{};
        std::memcpy(&v, file_ + position_, sizeof(T));
        position_ += sizeof(T);
        return v;
    }

    std::string bytes(std::uint64_t count, const char *what) {
        need(count, what);
        std::string s(file_ + position_, count);
        position_ += count;
        return s;
    }

    std::string string(const char *what) { return bytes(value<std::uint32_t>(what), what); }

    void skip(std::uint64_t bytes, const char *what) {
        need(bytes, what);
        position_ += bytes;
    }

  private:
    const char *file_;
    std::uint64_t position_, end_;
};

// The file, mapped read-only: the walk touches only the pages it reads (a header check reads a few).
class MappedFile {
  public:
    explicit MappedFile(const std::string &path) {
        const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) throw ReadError(std::strerror(errno));
        struct stat st {};
        if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
            ::close(fd);
            throw ReadError("not a regular file");
        }
        size_ = std::uint64_t(st.st_size);
        if (size_ > 0) {
            void *data = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
            if (data == MAP_FAILED) {
                ::close(fd);
                throw ReadError(std::strerror(errno));
            }
            data_ = static_cast<const char *>(data);
        }
        ::close(fd);
    }
    ~MappedFile() {
        if (data_) ::munmap(const_cast<char *>(data_), size_);
    }
    MappedFile(const MappedFile &) = delete;
    MappedFile &operator=(const MappedFile &) = delete;

    const char *data() const { return data_; }
    std::uint64_t size() const { return size_; }

  private:
    const char *data_ = nullptr;
    std::uint64_t size_ = 0;
};

// Bytes of the registered fixed-size metadata types: OpenVDB reads that many whatever the file's size field
// says, so a different size field would put OpenVDB's reading out of step with the walk.
const std::map<std::string, std::uint32_t> &fixedMetadataBytes() {
    static const std::map<std::string, std::uint32_t> bytes = {
        {"bool", 1},   {"int32", 4},  {"int64", 8},  {"float", 4},  {"double", 8}, {"vec2i", 8},
        {"vec2s", 8},  {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16},
        {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
    return bytes;
}

// The sizes OpenVDB reserves and decompresses for one array of the delayed-load metadata: `count` entries of
// `entryBytes`, stored raw (0) or blosc-compressed (its header says the uncompressed size at bytes 4-7).
void checkDelayedLoadArray(Cursor &meta, std::uint32_t count, std::uint32_t entryBytes, std::uint32_t stored) {
    if (stored == 0) {
        meta.skip(std::uint64_t(count) * entryBytes, "delayed-load array");
        return;
    }
    meta.need(stored, "compressed delayed-load array");
    if (stored < 16) throw ReadError("delayed-load array of " + std::to_string(stored) + " bytes (corrupted)");
    meta.value<std::uint32_t>("blosc header");
    const auto uncompressed = meta.value<std::uint32_t>("blosc header");
    // OpenVDB pads arrays under 128 bytes with zeros before compressing them
    const std::uint64_t expected = std::uint64_t(count) * entryBytes;
    if (uncompressed < expected || uncompressed > std::max<std::uint64_t>(expected, kBloscPadBytes))
        throw ReadError("delayed-load array says " + std::to_string(count) + " entries but holds " +
                        std::to_string(uncompressed) + " bytes (corrupted)");
    meta.skip(stored - 8, "compressed delayed-load array");
}

// OpenVDB's DelayedLoadMetadata ("file_delayed_load"): a leaf count and, per leaf, a mask code and a
// compressed size. OpenVDB allocates the count it reads (up to 36 GB) before checking anything, so the count
// must fit the grid: every leaf takes at least kMinLeafBytes of it.
std::int64_t checkDelayedLoad(Cursor &meta, std::uint64_t gridBytes) {
    if (meta.remaining() == 0) return -1;  // written empty
    const auto count = meta.value<std::uint32_t>("delayed-load leaf count");
    if (std::uint64_t(count) > gridBytes / kMinLeafBytes)
        throw ReadError("delayed-load metadata names " + std::to_string(count) + " leaves, more than a grid of " +
                        std::to_string(gridBytes) + " bytes holds (corrupted)");
    checkDelayedLoadArray(meta, count, 1, meta.value<std::uint32_t>("delayed-load mask size"));
    const auto sizes = meta.value<std::uint32_t>("delayed-load sizes size");
    if (sizes != 0xFFFFFFFFu) checkDelayedLoadArray(meta, count, 8, sizes);
    return count;
}

// A MetaMap: a count, then per entry a name, a type name, a byte count and the value. Returns the leaf count
// of its delayed-load metadata, -1 without one.
std::int64_t checkMetadata(Cursor &at, const char *what, std::uint64_t gridBytes) {
    std::int64_t delayedLoadLeaves = -1;
    const auto count = at.value<std::uint32_t>(what);
    if (std::uint64_t(count) * 12 > at.remaining())  // each entry takes at least three 4-byte lengths
        throw ReadError(std::string(what) + ": " + std::to_string(count) + " entries in " +
                        std::to_string(at.remaining()) + " bytes (corrupted)");
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::string name = at.string("metadata name");
        const std::string type = at.string("metadata type");
        const auto bytes = at.value<std::uint32_t>("metadata size");
        at.need(bytes, "metadata value");
        const auto fixed = fixedMetadataBytes().find(type);
        if (fixed != fixedMetadataBytes().end() && fixed->second != bytes)
            throw ReadError("metadata '" + name + "' of type " + type + " has " + std::to_string(bytes) +
                            " bytes instead of " + std::to_string(fixed->second) + " (corrupted)");
        if (type == "bool") {  // OpenVDB loads the byte as a bool: another value than 0 or 1 is undefined behaviour
            Cursor value = at.range(bytes);
            const auto b = value.value<std::uint8_t>("bool metadata");
            if (b > 1) throw ReadError("metadata '" + name + "' holds " + std::to_string(b) + " as a bool (corrupted)");
        }
        if (type == "__delayedload") {
            Cursor value = at.range(bytes);
            delayedLoadLeaves = checkDelayedLoad(value, gridBytes);
        }
        at.skip(bytes, "metadata value");
    }
    return delayedLoadLeaves;
}


// ---------------------------------------------------------------------------------------------------------
// Trees (tree/RootNode.h, InternalNode.h, LeafNode.h, io/Compression.h of OpenVDB 10): the walk reads what
// OpenVDB reads, in its order, and checks each length before OpenVDB trusts it. OpenVDB 10 reads an
// "uncompressed" chunk of the length the file gives before comparing it with the buffer's size (a heap
// overflow), allocates what a compressed length says, and hands blosc a header it does not check.

constexpr std::uint32_t kCompressZip = 0x1, kCompressActiveMask = 0x2, kCompressBlosc = 0x4;

struct ValueLayout {
    std::uint32_t bytes = 0;        // in memory, and as tiles, backgrounds and inactive values are stored
    std::uint32_t storedBytes = 0;  // as voxel and tile arrays are stored: half floats when the grid says so
    bool real = false;              // floating point: may be stored as half floats
};

// "Tree_float_5_4_3" and the other trees of plain values Firn reads; others (bool, mask, points) are refused.
ValueLayout valueLayout(const std::string &type, bool half) {
    static const std::map<std::string, std::pair<std::uint32_t, bool>> kValues = {
        {"Tree_float_5_4_3", {4, true}},  {"Tree_double_5_4_3", {8, true}}, {"Tree_int32_5_4_3", {4, false}},
        {"Tree_int64_5_4_3", {8, false}}, {"Tree_vec3s_5_4_3", {12, true}}, {"Tree_vec3d_5_4_3", {24, true}},
        {"Tree_vec3i_5_4_3", {12, false}}};
    const auto found = kValues.find(type);
    if (found == kValues.end()) throw ReadError("a grid of type " + type + ", which Firn does not read");
    ValueLayout v;
    v.bytes = found->second.first;
    v.real = found->second.second;
    const std::uint32_t components = v.bytes >= 12 ? 3 : 1;
    v.storedBytes = half && v.real ? 2 * components : v.bytes;
    return v;
}

// Bytes of a transform's map after its type name (math/Maps.h); frustum maps are refused.
std::uint64_t mapBytes(const std::string &type) {
    static const std::map<std::string, std::uint64_t> kBytes = {
        {"AffineMap", 128},        {"UnitaryMap", 128}, {"ScaleMap", 120}, {"UniformScaleMap", 120},
        {"TranslationMap", 24},    {"ScaleTranslateMap", 144}, {"UniformScaleTranslateMap", 144}};
    const auto found = kBytes.find(type);
    if (found == kBytes.end()) throw ReadError("a transform of type '" + type + "', which Firn does not read");
    return found->second;
}

std::uint64_t bitsOn(const std::string &mask) {
    std::uint64_t on = 0;
    for (unsigned char byte : mask) on += std::uint64_t(__builtin_popcount(byte));
    return on;
}

class TreeWalk {
  public:
    TreeWalk(Cursor &at, const ValueLayout &value, std::uint32_t compression)
        : at_(at), value_(value), compression_(compression) {}

    // Returns the number of leaves.
    std::uint64_t walk() {
        at_.value<std::int32_t>("buffer count");
        at_.skip(value_.bytes, "background");
        const auto tiles = at_.value<std::uint32_t>("root tile count");
        const auto children = at_.value<std::uint32_t>("root child count");
        if (std::uint64_t(tiles) * (12 + value_.bytes + 1) > at_.remaining() ||
            std::uint64_t(children) * (12 + 2 * 4096) > at_.remaining())
            throw ReadError(std::to_string(tiles) + " tiles and " + std::to_string(children) +
                            " nodes at the root of a tree of " + std::to_string(at_.remaining()) + " bytes (corrupted)");
        std::set<std::array<std::int32_t, 3>> keys;  // OpenVDB keeps one node per key: a repeated one loses a node
        for (std::uint32_t t = 0; t < tiles; ++t) {
            keys.insert(rootKey());
            at_.skip(value_.bytes, "tile value");
            const auto active = at_.value<std::uint8_t>("tile state");
            if (active > 1) throw ReadError("a tile state of " + std::to_string(active) + " (corrupted)");
        }
        std::array<std::int32_t, 3> previous{};
        for (std::uint32_t c = 0; c < children; ++c) {
            const std::array<std::int32_t, 3> key = rootKey();
            // OpenVDB reads the buffers in the order of its table (sorted by origin), the topology in the file's.
            if ((c > 0 && !(previous < key)) || keys.count(key) != 0)
                throw ReadError("root nodes out of order or repeated (corrupted)");
            previous = key;
            internalTopology(4096, 512);
        }
        if (keys.size() + children == 0) return 0;  // an empty tree: OpenVDB reads no buffers
        for (const std::string &mask : leafMasks_) {
            const std::string stored = bytes(64, "leaf mask");
            if (stored != mask) throw ReadError("a leaf's mask differs from its topology (corrupted)");
            values(512, bitsOn(mask), 64);
        }
        return leafMasks_.size();
    }

  private:
    std::array<std::int32_t, 3> rootKey() {
        std::array<std::int32_t, 3> key{};
        for (auto &k : key) {
            k = at_.value<std::int32_t>("root node origin");
            if ((k & 4095) != 0) throw ReadError("a root node origin off its 4096-voxel grid (corrupted)");
        }
        return key;
    }

    std::string bytes(std::uint64_t count, const char *what) {
        at_.need(count, what);
        return at_.bytes(count, what);
    }

    // An internal node with `maskBytes` masks (4096: 32^3 children, 512: 16^3), its tile values and children.
    void internalTopology(std::uint64_t maskBytes, std::uint64_t childMaskBytes) {
        const std::string childMask = bytes(maskBytes, "child mask");
        const std::string valueMask = bytes(maskBytes, "value mask");
        values(maskBytes * 8, bitsOn(valueMask), maskBytes);
        for (std::uint64_t i = 0; i < maskBytes * 8; ++i) {
            if (!((unsigned char)childMask[i / 8] >> (i % 8) & 1u)) continue;
            if (childMaskBytes == 0)
                leafMasks_.push_back(bytes(64, "leaf mask"));
            else
                internalTopology(childMaskBytes, 0);
        }
    }

    // io::readCompressedValues: `count` values, `active` of them on in the node's mask of `maskBytes`.
    void values(std::uint64_t count, std::uint64_t active, std::uint64_t maskBytes) {
        const auto code = at_.value<std::int8_t>("value code");
        if (code == 2 || code == 4 || code == 5) at_.skip(value_.bytes, "inactive value");
        if (code == 5) at_.skip(value_.bytes, "inactive value");
        if (code == 3 || code == 4 || code == 5) at_.skip(maskBytes, "selection mask");
        const std::uint64_t stored = (compression_ & kCompressActiveMask) && code != 6 ? active : count;
        if (stored == 0 && value_.real && value_.storedBytes != value_.bytes) return;  // HalfReader reads nothing
        const std::uint64_t expected = stored * value_.storedBytes;
        if (!(compression_ & (kCompressZip | kCompressBlosc))) {
            at_.skip(expected, "values");
            return;
        }
        const auto length = at_.value<std::int64_t>("compressed length");
        if (length <= 0) {
            if (std::uint64_t(-length) != expected)
                throw ReadError("an uncompressed chunk of " + std::to_string(-length) + " bytes where " +
                                std::to_string(expected) + " belong (corrupted)");
            at_.skip(expected, "values");
            return;
        }
        Cursor chunk = at_.range(std::uint64_t(length));
        if (compression_ & kCompressBlosc) {
            // blosc trusts its header: its sizes must agree with the chunk and the values it holds
            if (length < 16) throw ReadError("a compressed chunk of " + std::to_string(length) + " bytes (corrupted)");
            chunk.skip(4, "blosc header");
            const auto uncompressed = chunk.value<std::uint32_t>("blosc header");
            chunk.skip(4, "blosc header");
            const auto compressed = chunk.value<std::uint32_t>("blosc header");
            if (uncompressed != expected || compressed != std::uint64_t(length))
                throw ReadError("a compressed chunk whose header disagrees with its size (corrupted)");
        }
        at_.skip(std::uint64_t(length), "compressed values");
    }

    Cursor &at_;
    ValueLayout value_;
    std::uint32_t compression_;
    std::vector<std::string> leafMasks_;  // in file order, to compare with the masks before the voxels
};

}  // namespace

VdbLayout checkVdbLayout(const std::string &path, VdbCheck depth) {
    VdbLayout layout;
    try {
        const MappedFile file(path);
        const std::uint64_t size = file.size();
        layout.fileBytes = size;
        Cursor at(file.data(), 0, size);
        at.need(kHeaderBytes, "header");
        if (at.value<std::int64_t>("magic number") != kMagic) throw ReadError("not a VDB file");
        layout.formatVersion = at.value<std::uint32_t>("format version");
        if (layout.formatVersion < kFirstWalkedVersion)
            throw ReadError("VDB format " + std::to_string(layout.formatVersion) +
                            " (OpenVDB before 3.0) is not supported: write it again with a newer OpenVDB");
        at.skip(8, "library version");
        if (at.value<char>("grid offsets flag") == 0)
            throw ReadError("a VDB stream without grid offsets (written as a stream, not as a file)");
        at.skip(36, "UUID");
        checkMetadata(at, "file metadata", size);
        const auto grids = at.value<std::int32_t>("grid count");
        if (grids < 0 || std::uint64_t(grids) * 36 > at.remaining())  // a descriptor takes at least 36 bytes
            throw ReadError("grid count " + std::to_string(grids) + " (corrupted)");
        for (std::int32_t g = 0; g < grids; ++g) {
            VdbGridLayout grid;
            grid.uniqueName = at.string("grid name");
            grid.type = at.string("grid type");
            const std::string parent = at.string("instance parent name");
            const auto gridPos = at.value<std::int64_t>("grid offset");
            const auto blockPos = at.value<std::int64_t>("grid offset");
            const auto endPos = at.value<std::int64_t>("grid offset");
            const bool instance = !parent.empty();  // an instance has metadata and a transform, no tree
            const std::int64_t treeEnd = instance ? endPos : blockPos;
            if (gridPos < std::int64_t(at.position()) || treeEnd < gridPos || endPos < treeEnd ||
                std::uint64_t(endPos) > size)
                throw ReadError("grid '" + grid.uniqueName + "' lies at bytes " + std::to_string(gridPos) + "-" +
                                std::to_string(endPos) + " of a file of " + std::to_string(size) +
                                " bytes (truncated or corrupted)");
            grid.gridBytes = std::uint64_t(endPos - gridPos);
            Cursor inGrid(file.data(), std::uint64_t(gridPos), std::uint64_t(endPos));
            const auto compression = inGrid.value<std::uint32_t>("grid compression");
            Cursor meta = inGrid.range(std::uint64_t(treeEnd - gridPos) - 4);
            const std::int64_t delayedLoadLeaves = checkMetadata(meta, "grid metadata", grid.gridBytes);
            inGrid.skip(meta.position() - inGrid.position(), "grid metadata");
            const std::string transform = inGrid.string("transform type");
            if (depth == VdbCheck::Trees) inGrid.skip(mapBytes(transform), "transform");
            if (!instance && depth == VdbCheck::Trees) {
                const std::string halfSuffix = "_HalfFloat";
                std::string treeType = grid.type;
                const bool half = treeType.size() > halfSuffix.size() &&
                                  treeType.compare(treeType.size() - halfSuffix.size(), halfSuffix.size(), halfSuffix) == 0;
                if (half) treeType.resize(treeType.size() - halfSuffix.size());
                const std::uint64_t leaves = TreeWalk(inGrid, valueLayout(treeType, half), compression).walk();
                // OpenVDB looks leaves up in it by their index, asserting they are there (an abort in Debian's build)
                if (delayedLoadLeaves >= 0 && std::uint64_t(delayedLoadLeaves) != leaves)
                    throw ReadError("delayed-load metadata for " + std::to_string(delayedLoadLeaves) +
                                    " leaves in a tree of " + std::to_string(leaves) + " (corrupted)");
            }
            layout.grids.push_back(grid);
            at = Cursor(file.data(), std::uint64_t(endPos), size);  // the next descriptor follows the grid
        }
    } catch (const ReadError &e) {
        throw ReadError("cannot read " + path + ": " + e.what());
    }
    return layout;
}

}  // namespace firn
