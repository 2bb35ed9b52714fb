#include "firn/io/vdb_archive.h"

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "firn/util/openvdb_library.h"

namespace firn {

namespace {

std::filesystem::path tempPath(const std::string &name) {
    const auto folder =
        std::filesystem::temp_directory_path() / ("firn_vdb_archive_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(folder);
    return folder / name;
}

std::string bytesOf(const std::filesystem::path &path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// One leaf of each kind OpenVDB's mask compression tells apart (io/Compression.h): all active; the rest at the
// background; at -background too (a level set's inside); at one other value; at two others; at many.
template <typename GridT>
typename GridT::Ptr leavesOfEveryKind(const std::string &name, typename GridT::ValueType background,
                                      typename GridT::ValueType other, openvdb::GridClass kind) {
    auto grid = GridT::create(background);
    grid->setName(name);
    grid->setGridClass(kind);
    auto &tree = grid->tree();
    for (int leaf = 0; leaf < 6; ++leaf) {
        for (int v = 0; v < 512; ++v) {
            const openvdb::Coord ijk(8 * leaf + (v & 7), (v >> 3) & 7, v >> 6);
            const auto value = other * float(1 + v % 13);
            const bool active = leaf == 0 || v % 3 == 0;
            if (active) {
                tree.setValueOn(ijk, value);
                continue;
            }
            const typename GridT::ValueType inactive[] = {background, v % 2 ? background : -background,
                                                          other, v % 2 ? other : other * 2.0f, value};
            tree.setValueOff(ijk, inactive[std::min(leaf - 1, 4)]);
        }
    }
    return grid;
}

}  // namespace

TEST(VdbArchive, WritesTheBytesOpenVdbWritesButTheUuid) {
    // OpenVDB's own write is the reference: the same header, metadata, delayed-load table (each leaf's mask
    // compression and compressed size), topology and leaf buffers, for the grid types and settings Firn writes.
    initializeOpenVdb();
    auto fog = leavesOfEveryKind<openvdb::FloatGrid>("density", 0.0f, 2.5f, openvdb::GRID_FOG_VOLUME);
    auto levelSet = leavesOfEveryKind<openvdb::FloatGrid>("surface", 0.03f, 0.01f, openvdb::GRID_LEVEL_SET);
    auto half = leavesOfEveryKind<openvdb::FloatGrid>("half", 1.0f, 0.5f, openvdb::GRID_UNKNOWN);
    half->setSaveFloatAsHalf(true);
    auto vectors = leavesOfEveryKind<openvdb::Vec3SGrid>("light", openvdb::Vec3s(0.0f), openvdb::Vec3s(1, 2, 3),
                                                         openvdb::GRID_UNKNOWN);
    auto flags = openvdb::BoolGrid::create(false);
    flags->setName("flags");
    flags->tree().setValueOn(openvdb::Coord(3, 4, 5), true);
    auto empty = openvdb::FloatGrid::create(0.0f);
    empty->setName("density");  // a repeated name: OpenVDB makes both unique
    auto instance = openvdb::gridPtrCast<openvdb::FloatGrid>(fog->copyGrid());  // its tree shared: an instance
    instance->setName("instance");
    const openvdb::GridPtrVec grids{fog, levelSet, half, vectors, flags, empty, instance};
    openvdb::MetaMap meta;
    meta.insertMeta("creator", openvdb::StringMetadata("test"));

    const auto reference = tempPath("openvdb.vdb"), ours = tempPath("firn.vdb");
    openvdb::io::File(reference.string()).write(grids, meta);
    {
        std::ofstream out(ours, std::ios::binary);
        writeVdbArchive(out, grids, meta);
    }
    std::string expected = bytesOf(reference), got = bytesOf(ours);
    ASSERT_EQ(got.size(), expected.size());
    // The header's UUID: 36 characters after the magic number, versions and the offsets flag (21 bytes).
    constexpr std::size_t kUuidStart = 21, kUuidLength = 36;
    got.replace(kUuidStart, kUuidLength, kUuidLength, '-'), expected.replace(kUuidStart, kUuidLength, kUuidLength, '-');
    EXPECT_TRUE(got == expected) << "the files differ at byte "
                                 << std::distance(got.begin(),
                                                  std::mismatch(got.begin(), got.end(), expected.begin()).first);

    // Read back delayed (leaves loaded on demand, through the table): the values come back.
    openvdb::io::File file(ours.string());
    file.open(/*delayLoad=*/true);
    const auto back = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("surface"));
    file.close();
    ASSERT_TRUE(back);
    for (auto leaf = levelSet->tree().cbeginLeaf(); leaf; ++leaf)
        for (openvdb::Index v = 0; v < leaf->SIZE; v += 7)
            ASSERT_EQ(back->tree().getValue(leaf->offsetToGlobalCoord(v)), leaf->getValue(v)) << leaf->origin();
    std::filesystem::remove_all(reference.parent_path());
}

}  // namespace firn
