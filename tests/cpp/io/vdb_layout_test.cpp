// Corrupted VDB files fail in Firn's layout check, with ReadError, before OpenVDB trusts their lengths
// (issue 11: allocations of gigabytes, a heap overflow and an assertion in OpenVDB 10).
#include "firn/io/vdb_layout.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/io/vdb_io.h"
#include "firn/util/error.h"

namespace firn {

namespace {

std::filesystem::path tempPath(const std::string &name) {
    const auto dir = std::filesystem::temp_directory_path() / ("firn_vdb_layout_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return dir / name;
}

// A density grid of a few leaves and a baked-like Vec3 grid, as Firn writes them.
std::string writeSnowFile(const std::string &name) {
    auto density = test::densityGrid(0.02);
    for (int i = 0; i < 40; ++i) density->tree().setValue({i, (i * 7) % 23, -(i % 5)}, 250.0f + float(i));
    auto source = openvdb::Vec3SGrid::create();
    source->setName("firn_source");
    source->setTransform(density->transform().copy());
    for (int i = 0; i < 40; ++i) source->tree().setValue({i, (i * 7) % 23, -(i % 5)}, openvdb::Vec3s(1, 2, 3));
    const std::string path = tempPath(name).string();
    writeGrids(path, {density, source});
    return path;
}

std::string bytesOf(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

void writeBytes(const std::string &path, const std::string &bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

void putU32(std::string &bytes, std::size_t at, std::uint32_t value) { std::memcpy(&bytes[at], &value, 4); }

// The message of the ReadError `call` throws, or "" when it throws none.
template <typename Call>
std::string readErrorOf(Call call) {
    try {
        call();
    } catch (const ReadError &e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(VdbLayout, AcceptsWhatFirnWritesAtBothDepths) {
    const std::string path = writeSnowFile("good.vdb");
    for (const VdbCheck depth : {VdbCheck::Header, VdbCheck::Trees}) {
        const VdbLayout layout = checkVdbLayout(path, depth);
        ASSERT_EQ(layout.grids.size(), 2u);
        EXPECT_EQ(layout.grids[0].uniqueName, "density");
        EXPECT_EQ(layout.grids[1].type, "Tree_vec3s_5_4_3");
        EXPECT_EQ(layout.fileBytes, std::filesystem::file_size(path));
    }
    EXPECT_EQ(readGrids(path).size(), 2u);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

// A corrupted string length asked OpenVDB for up to 4 GB before it read a byte of it.
TEST(VdbLayout, AHugeMetadataLengthIsRefusedBeforeOpenVdbAllocatesIt) {
    const std::string path = writeSnowFile("huge_length.vdb");
    std::string bytes = bytesOf(path);
    putU32(bytes, 57 + 4, 0xFFFFFF00u);  // the first file metadata name's length, after the header and the count
    writeBytes(path, bytes);
    for (const VdbCheck depth : {VdbCheck::Header, VdbCheck::Trees})
        EXPECT_NE(readErrorOf([&] { checkVdbLayout(path, depth); }).find("metadata name of 4294967040 bytes where"),
                  std::string::npos);
    EXPECT_NE(readErrorOf([&] { readGrids(path); }).find("cannot read " + path), std::string::npos);
    EXPECT_NE(readErrorOf([&] { gridNames(path); }).find("metadata name"), std::string::npos);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

// OpenVDB 10 asserts (aborts, in Debian's build) when the delayed-load table is shorter than the tree,
// and allocates what its count says (up to 36 GB).
TEST(VdbLayout, ADelayedLoadTableThatDoesNotMatchTheTreeIsRefused) {
    const std::string path = writeSnowFile("delayed_load.vdb");
    std::string bytes = bytesOf(path);
    const std::string type = "__delayedload";
    const std::size_t at = bytes.find(type);
    ASSERT_NE(at, std::string::npos);
    const std::size_t count = at + type.size() + 4;  // after the type name and the value's byte count
    std::uint32_t leaves = 0;
    std::memcpy(&leaves, &bytes[count], 4);
    ASSERT_GT(leaves, 0u);
    putU32(bytes, count, leaves - 1);
    writeBytes(path, bytes);
    EXPECT_NE(readErrorOf([&] { readGrids(path); }).find("delayed-load"), std::string::npos);
    putU32(bytes, count, 0x7FFFFFFFu);
    writeBytes(path, bytes);
    EXPECT_NE(readErrorOf([&] { readGrids(path); }).find("more than a grid of"), std::string::npos);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

// OpenVDB loads a bool metadata's byte as a bool: 105 is undefined behaviour (UBSan, the asan fuzz run).
TEST(VdbLayout, ABoolMetadataOtherThanZeroOrOneIsRefused) {
    const std::string path = writeSnowFile("bool.vdb");
    std::string bytes = bytesOf(path);
    const std::string name = "firn_half_voxel_shift";
    const std::size_t at = bytes.find(name);
    ASSERT_NE(at, std::string::npos);
    const std::size_t value = at + name.size() + 4 + 4 + 4;  // the type's length, "bool", the value's byte count
    ASSERT_EQ(bytes.substr(at + name.size() + 4, 4), "bool");
    bytes[value] = char(105);
    writeBytes(path, bytes);
    EXPECT_NE(readErrorOf([&] { gridNames(path); }).find("holds 105 as a bool"), std::string::npos);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

// A truncated file is found from its grid descriptors alone: the cheap check the add-on runs on load.
TEST(VdbLayout, ATruncatedFileFailsTheHeaderCheck) {
    const std::string path = writeSnowFile("truncated.vdb");
    std::filesystem::resize_file(path, std::filesystem::file_size(path) - 1);
    EXPECT_NE(readErrorOf([&] { checkVdbLayout(path, VdbCheck::Header); }).find("truncated or corrupted"),
              std::string::npos);
    EXPECT_NE(readErrorOf([&] { gridNames(path); }).find("truncated or corrupted"), std::string::npos);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

// Reading and writing fail with different types, so a call that does both says which failed.
TEST(VdbLayout, ReadAndWriteFailuresHaveTheirOwnTypes) {
    EXPECT_THROW(readGrids("/nonexistent/firn/none.vdb"), ReadError);
    EXPECT_THROW(gridNames("/nonexistent/firn/none.vdb"), ReadError);
    const std::string path = writeSnowFile("types.vdb");
    const auto blocker = tempPath("blocker");
    std::ofstream(blocker.string()) << "a file where a folder should be";
    EXPECT_THROW(writeGrids((blocker / "x.vdb").string(), readGrids(path)), WriteError);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

}  // namespace firn
