#include "firn/io/vdb_io.h"
#include "firn/util/openvdb_library.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/util/error.h"

namespace firn {

namespace {

std::filesystem::path tempPath(const std::string &name) {
    return std::filesystem::temp_directory_path() / ("firn_vdb_io_test_" + std::to_string(::getpid())) / name;
}

openvdb::FloatGrid::Ptr cubeWithTile(double voxelSize) {
    auto grid = test::densityGrid(voxelSize);
    grid->tree().addTile(1, openvdb::Coord(0), 250.0f, true);  // one 8^3 tile of snow, 250 kg/m^3
    grid->tree().setValue(openvdb::Coord(20, 0, 0), 100.0f);
    return grid;
}

}  // namespace

TEST(VdbIo, RoundTripKeepsValuesAndInMemoryTransform) {
    const auto path = tempPath("roundtrip.vdb");
    writeGrids(path.string(), {cubeWithTile(0.1)});
    const openvdb::GridPtrVec grids = readGrids(path.string());
    ASSERT_EQ(grids.size(), 1u);
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[0]);
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->getName(), "density");
    EXPECT_FLOAT_EQ(grid->tree().getValue(openvdb::Coord(3, 4, 5)), 250.0f);
    EXPECT_FLOAT_EQ(grid->tree().getValue(openvdb::Coord(20, 0, 0)), 100.0f);
    const openvdb::Vec3d centre = grid->indexToWorld(openvdb::Coord(20, 0, 0));
    EXPECT_NEAR(centre.x(), 2.0, 1e-12);  // unshifted on the way back in
    std::filesystem::remove_all(path.parent_path());
}

TEST(VdbIo, ManyLeavesComeBackEachWithItsOwnValuesAndMask) {
    // writeGrids compresses the leaf buffers in chunks on several threads and writes them in the tree's order:
    // a leaf's values read back into another leaf if that order slipped. 1,000 leaves (16 chunks), each with
    // values of its own, some voxels off (with values other than the background, which the file keeps).
    initializeOpenVdb();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    for (int l = 0; l < 1000; ++l) {
        const openvdb::Coord origin(8 * (l % 10), 8 * (l / 10 % 10), 8 * (l / 100) - 40);
        for (int v = 0; v < 512; v += 1 + l % 7) {
            const openvdb::Coord ijk = origin.offsetBy(v & 7, (v >> 3) & 7, v >> 6);
            grid->tree().setValue(ijk, float(l) + 0.001f * float(v));
            if (v % 5 == 0) grid->tree().setValueOff(ijk);
        }
    }
    const auto path = tempPath("leaves.vdb");
    writeGrids(path.string(), {grid});
    const auto back = openvdb::gridPtrCast<openvdb::FloatGrid>(readGrids(path.string()).at(0));
    ASSERT_TRUE(back);
    ASSERT_EQ(back->tree().leafCount(), 1000u);
    for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
        const auto *read = back->tree().probeConstLeaf(leaf->origin());
        ASSERT_NE(read, nullptr);
        EXPECT_EQ(read->getValueMask(), leaf->getValueMask()) << leaf->origin();
        for (openvdb::Index v = 0; v < leaf->SIZE; ++v)
            ASSERT_EQ(read->getValue(v), leaf->getValue(v)) << leaf->origin() << " voxel " << v;
    }
}

TEST(VdbIo, FileHasNoTilesAndIsShiftedHalfAVoxelForCycles) {
    const auto path = tempPath("cycles.vdb");
    writeGrids(path.string(), {cubeWithTile(0.1)});
    openvdb::io::File file(path.string());
    file.open();
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
    file.close();
    EXPECT_EQ(grid->tree().activeTileCount(), 0u);  // Cycles renders tiles as nothing
    EXPECT_EQ(grid->activeVoxelCount(), 8u * 8u * 8u + 1u);
    // Cycles centres voxel i at (i + 1/2) h + translation: the file's translation is -h/2.
    EXPECT_NEAR(grid->indexToWorld(openvdb::Coord(0)).x(), -0.05, 1e-12);
    std::filesystem::remove_all(path.parent_path());
}

TEST(VdbIo, FailedWriteLeavesNoFileAndThrows) {
    const auto dir = tempPath("blocked");
    std::filesystem::create_directories(dir.parent_path());
    std::ofstream(dir.string()) << "a file where a folder should be";
    EXPECT_THROW(writeGrids((dir / "x.vdb").string(), {cubeWithTile(0.1)}), IoError);
    EXPECT_FALSE(std::filesystem::exists(dir / "x.vdb"));
    std::filesystem::remove_all(dir.parent_path());
}

TEST(VdbIo, FullDiskLeavesThePreviousFileAndNoTemporaryFile) {
    // The temporary file is a link to /dev/full: every write fails with ENOSPC, as on a full disk.
    const auto path = tempPath("full.vdb");
    writeGrids(path.string(), {cubeWithTile(0.1)});
    const auto before = std::filesystem::file_size(path);
    const auto temp = std::filesystem::path(path.string() + ".tmp" + std::to_string(::getpid()));
    std::filesystem::create_symlink("/dev/full", temp);
    try {
        writeGrids(path.string(), {cubeWithTile(0.2)});
        ADD_FAILURE() << "a write to a full disk did not throw";
    } catch (const IoError &e) {
        EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(temp)));
    EXPECT_EQ(std::filesystem::file_size(path), before);
    EXPECT_NEAR(readGrids(path.string())[0]->voxelSize()[0], 0.1, 1e-12);  // the previous file, intact
    std::filesystem::remove_all(path.parent_path());
}

TEST(VdbIo, RemoveGridsKeepsTheOthersAsStored) {
    const auto path = tempPath("remove.vdb");
    auto source = openvdb::Vec3SGrid::create();
    source->setName("firn_source");
    source->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    source->tree().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 2, 3));
    auto surface = cubeWithTile(0.1);
    surface->setName("surface");
    writeGrids(path.string(), {cubeWithTile(0.1), surface, source});

    EXPECT_EQ(removeGrids(path.string(), {"firn_source", "firn_source_x"}), std::vector<std::string>{"firn_source"});
    const openvdb::GridPtrVec grids = readGrids(path.string());
    ASSERT_EQ(grids.size(), 2u);
    EXPECT_EQ(grids[0]->getName(), "density");
    EXPECT_EQ(grids[1]->getName(), "surface");
    auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[0]);
    EXPECT_EQ(density->activeVoxelCount(), 8u * 8u * 8u + 1u);
    EXPECT_FLOAT_EQ(density->tree().getValue(openvdb::Coord(20, 0, 0)), 100.0f);
    EXPECT_NEAR(density->indexToWorld(openvdb::Coord(20, 0, 0)).x(), 2.0, 1e-12);  // not shifted twice

    const auto stamp = std::filesystem::last_write_time(path);
    EXPECT_TRUE(removeGrids(path.string(), {"firn_source"}).empty());  // nothing to remove: not rewritten
    EXPECT_EQ(std::filesystem::last_write_time(path), stamp);
    EXPECT_THROW(removeGrids(path.string(), {"density", "surface"}), InvalidArgument);
    EXPECT_EQ(readGrids(path.string()).size(), 2u);
    EXPECT_THROW(removeGrids((path.parent_path() / "none.vdb").string(), {"density"}), IoError);
    std::filesystem::remove_all(path.parent_path());
}

TEST(VdbIo, ReadingATruncatedFileThrowsIoError) {
    const auto path = tempPath("truncated.vdb");
    auto surface = cubeWithTile(0.1);
    surface->setName("surface");
    writeGrids(path.string(), {cubeWithTile(0.1), surface});
    const auto size = std::filesystem::file_size(path);
    for (const double kept : {0.95, 0.6, 0.3}) {  // shorter and shorter
        std::filesystem::resize_file(path, static_cast<std::uintmax_t>(kept * size));
        EXPECT_THROW(readGrids(path.string()), IoError) << kept;
        EXPECT_THROW(removeGrids(path.string(), {"surface"}), IoError) << kept;
    }
    std::filesystem::remove_all(path.parent_path());
}

TEST(VdbIo, ReadingAMissingFileThrowsIoError) {
    EXPECT_THROW(readGrids("/nonexistent/firn/none.vdb"), IoError);
}

// Fuzzing (issue 11): a file cut short inside its header read as a file of no grids, as if it were fine.
TEST(VdbIo, TruncatedHeaderThrowsIoError) {
    const std::string path = tempPath("truncated.vdb").string();
    writeGrids(path, {cubeWithTile(0.1)});
    std::filesystem::resize_file(path, 20);
    EXPECT_THROW(readGrids(path), IoError);
    std::filesystem::remove(path);
}

}  // namespace firn
