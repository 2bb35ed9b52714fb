// Esc during any stage of a bake: cancelled when a stage first shows, the bake stops within that stage.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "firn/io/vdb_io.h"
#include "firn/transport/bake.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/slab.h"
#include "firn/util/error.h"

namespace firn {

namespace {

// A slab under a small lump that hides part of its sky: every stage of a bake runs, the gathering between snow
// surfaces too.
Scene slabUnderLump() {
    constexpr double kVoxel = 0.01;     // m
    constexpr float kDensity = 300.0f;  // kg/m^3
    openvdb::FloatGrid::Ptr density = makeSlabDensity(kVoxel, 12, 6, kDensity);
    for (int x = 0; x < 3; ++x)
        for (int y = 0; y < 3; ++y) density->tree().setValue(openvdb::Coord(x, y, 5), kDensity);  // above the slab
    Scene scene;
    scene.medium = std::make_shared<Medium>(density, VolumeOptics{2000.0 / kDensity, Rgb(0.999), 0.85});
    scene.sky.radiance = Rgb(0.5);
    scene.suns = {SunLight{{0.6, 0.0, 0.8}, Rgb(1.0), 0.0}};
    return scene;
}

// The stages an uncancelled bake shows, in order, each once (every report called back: interval 0).
std::vector<std::string> stagesOf(const Scene &scene, const BakeSettings &settings) {
    std::vector<std::string> stages;
    Progress progress(
        [&](double, const std::string &stage) {
            if (stages.empty() || stages.back() != stage) stages.push_back(stage);
        },
        0.0);
    bakeScattering(scene, settings, &progress);
    return stages;
}

}  // namespace

// Cancelled as each stage first shows, the bake throws Cancelled before any later stage shows (and returns no
// grids); "Done" comes after the work, where the binding's write checks (the test below).
TEST(BakeCancel, EveryStageStopsWithinItself) {
    const Scene scene = slabUnderLump();
    const BakeSettings settings{BakeQuality::Draft, 5};
    const std::vector<std::string> stages = stagesOf(scene, settings);
    for (const char *expected : {"Finding the snow's voxels", kLightAndTraceStage, "Solving multiple scattering",
                                 "Gathering light between snow surfaces", "Finding the light leaving the surface",
                                 "Writing the grids", "Done"})
        EXPECT_NE(std::find(stages.begin(), stages.end(), expected), stages.end()) << expected;
    for (const std::string &stage : stages) {
        if (stage == "Done") continue;
        std::string last;
        Progress progress(
            [&](double, const std::string &shown) {
                last = shown;
                if (shown == stage) progress.cancel();
            },
            0.0);
        EXPECT_THROW(bakeScattering(scene, settings, &progress), Cancelled) << stage;
        EXPECT_EQ(last, stage);
    }
}

// A write cancelled while the grids are compressed leaves the file as it was, and no temporary file beside it.
TEST(BakeCancel, CancelledWriteKeepsThePreviousFile) {
    const std::filesystem::path folder = std::filesystem::temp_directory_path() / "firn_bake_cancel_test";
    std::filesystem::remove_all(folder);
    const std::string path = (folder / "snow.vdb").string();
    const Scene scene = slabUnderLump();
    const BakedGrids baked = bakeScattering(scene, BakeSettings{BakeQuality::Draft, 5});
    const openvdb::FloatGrid::Ptr density = scene.medium->density().deepCopy();
    writeGrids(path, {density});
    const std::vector<std::string> names = gridNames(path);
    const auto bytes = std::filesystem::file_size(path);
    Progress cancelled;
    cancelled.cancel();
    openvdb::GridPtrVec grids{density};
    for (const auto &grid : baked.grids()) grids.push_back(grid);
    EXPECT_THROW(writeGrids(path, grids, &cancelled), Cancelled);
    EXPECT_EQ(gridNames(path), names);
    EXPECT_EQ(std::filesystem::file_size(path), bytes);
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(folder), std::filesystem::directory_iterator()), 1);
    std::filesystem::remove_all(folder);
}

// One voxel's or one face's gathered paths (MonteCarloReference::sourceIn, faceSourceIn) run for seconds in dense
// snow, so a cancel while they run stops them within their paths. Each is asked for far more paths than it could trace
// before the cancel (minutes to hours of tracking in this snow of optical depth 20 per voxel) and throws Cancelled
// instead of running on (sourceIn draws nothing before its paths: only the check among them can stop it).
TEST(BakeCancel, GatheredPathsStopWithinThemselves) {
    const Scene scene = slabUnderLump();
    const MonteCarloReference reference(scene);
    const openvdb::Coord top(6, 6, -1);  // the slab's top layer, away from the lump
    ASSERT_GT(scene.medium->density().tree().getValue(top), 0.0f);
    const auto cancelledWhileRunning = [](const auto &gather) {
        Progress progress;
        std::thread cancel([&] {
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
            progress.cancel();
        });
        EXPECT_THROW(gather(SubProgress(&progress, 0.0, 1.0)), Cancelled);
        cancel.join();
    };
    cancelledWhileRunning([&](const SubProgress &progress) {
        return reference.sourceIn(top, 1 << 30, 1, 0, Gathering::Spread, progress);
    });
    cancelledWhileRunning([&](const SubProgress &progress) {
        return reference.faceSourceIn(top, 5, 1 << 20, 1, 0, progress);  // +z: the top's face open to the sky
    });
}

}  // namespace firn
