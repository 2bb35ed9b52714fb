// The traced voxels' paths (bake_traced_voxels.h, planGathering): where the plan holds the preset's paths, the voxels
// the renderer draws rather than scatters (sigma_t h at least BakedGrids::kScatterOpticalDepth) take twice as many, up
// to the preset's cheap paths; none more where the budget already cuts the paths; the faces' and lit faces' paths
// (addFaceSources); a small scene's paths raised within its traced work, unless light tracing took it.
#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

#include "box_scene.h"
#include "firn/transport/bake_preset.h"
#include "firn/transport/bake_traced_voxels.h"

namespace firn {

namespace {

const openvdb::CoordBBox kLump(openvdb::Coord(0), openvdb::Coord(1));

// A 2 x 2 x 2 lump of sigma_t h 8 of forward scattering snow (as spray_dense's small lumps) under a sun 30 degrees
// high.
Scene smallLump() {
    return test::boxScene(kLump, float(8.0 / (10.0 * test::kBoxVoxel)), VolumeOptics{10.0, Rgb(0.999), 0.85},
                          glm::dvec3(0.866, 0.0, 0.5));
}

std::vector<openvdb::Coord> lumpVoxels() {
    std::vector<openvdb::Coord> voxels;
    for (const openvdb::Coord &c : kLump) voxels.push_back(c);
    return voxels;
}

// FINAL's preset but for its traced paths and the cheap paths' cap.
bake::Preset preset(int traced, int cheap, double smallScene = 0.0) {
    return {9, 4, 1e-5, 0, 1, traced, cheap, true, 1.0, smallScene};
}

}  // namespace

TEST(GatheringPlan, TheVoxelsTheRendererDrawsTakeTwiceThePaths) {
    const bake::GatheringPlan plan = bake::planGathering(smallLump(), preset(64, 1 << 20), lumpVoxels(), 1);
    ASSERT_GE(plan.paths, 64);
    EXPECT_EQ(plan.drawnPaths, 2 * plan.paths);
}

TEST(GatheringPlan, TheDrawnVoxelsStayWithinTheCheapPathsCap) {
    const bake::GatheringPlan plan = bake::planGathering(smallLump(), preset(64, 64), lumpVoxels(), 1);
    ASSERT_EQ(plan.paths, 64);
    EXPECT_EQ(plan.drawnPaths, 64);
}

// A preset asking more paths than the budget affords: the plan is cut, and the drawn voxels take no more.
TEST(GatheringPlan, NoMorePathsWhereTheBudgetCutsThem) {
    const bake::GatheringPlan plan = bake::planGathering(smallLump(), preset(1 << 30, 1 << 30), lumpVoxels(), 1);
    ASSERT_GT(plan.paths, 0);
    ASSERT_LT(plan.paths, 1 << 30);
    EXPECT_EQ(plan.drawnPaths, plan.paths);
}

// A gathered lump's faces take kFacePathsPerVoxelPath times the voxel's paths and its lit faces kLitFacePaths times
// the faces' multiple of half the voxel's (addFaceSources), up to the preset's cheap paths: the faces of 256 paths per
// voxel 512 and their lit faces 1400 where the cheap cap is wide, FINAL's 1024 each; DRAFT's 64 none more. Before, the
// faces took half the voxel's paths and the lit faces kLitFacePaths (docs/benchmarks.md, face-pilot).
TEST(GatheringPlan, FacesTakeAMultipleOfTheVoxelsPathsUpToTheCheapPaths) {
    const bake::GatheringPlan wide = bake::planGathering(smallLump(), preset(256, 1 << 20), lumpVoxels(), 1);
    ASSERT_GE(wide.paths, 256);
    EXPECT_EQ(wide.facePaths, bake::kFacePathsPerVoxelPath * wide.paths);
    EXPECT_EQ(wide.litFacePaths, 2 * bake::kFacePathsPerVoxelPath * bake::kLitFacePaths);
    const bake::GatheringPlan final = bake::planGathering(smallLump(), preset(256, 1024), lumpVoxels(), 1);
    ASSERT_GE(final.paths, 512);
    EXPECT_EQ(final.facePaths, 1024);
    EXPECT_EQ(final.litFacePaths, 1024);
    const bake::GatheringPlan draft = bake::planGathering(smallLump(), preset(64, 64), lumpVoxels(), 1);
    EXPECT_EQ(draft.facePaths, 64);
    EXPECT_EQ(draft.litFacePaths, 64);
}

// The faces take the plan's paths within what the voxels' paths leave of kMaxTracedSteps and of a small scene's
// traced work, down to a quarter of the voxel's, never more than the faces' own (addFaceSources prices them at their
// own steps per path).
TEST(GatheringPlan, TheFacesShareWhatTheVoxelsLeaveOfTheBudget) {
    const bake::GatheringPlan plan{256, bake::kMaxTracedSteps - 1e6, 256, 512, 1024};
    const bake::FaceGathering how = bake::gatheredVoxelFaces(plan);
    EXPECT_EQ(how.paths, 512);
    EXPECT_EQ(how.fewestPaths, 64);
    EXPECT_DOUBLE_EQ(how.budget, 1e6);
    EXPECT_EQ(how.litPaths, 1024);
    const bake::GatheringPlan small{256, bake::kMaxTracedSteps - 1e6, 256, 512, 1024, 3e7};
    EXPECT_DOUBLE_EQ(bake::gatheredVoxelFaces(small).budget, 3.1e7);
    const bake::GatheringPlan raised{16384, 1e8, 16384, 1024, 1024, 0.0};
    EXPECT_EQ(bake::gatheredVoxelFaces(raised).fewestPaths, 1024);
}

// A small scene's paths are as many as its traced work affords (Preset::smallSceneTracedSteps), up to
// kMostTracedShare times the cheap paths, never fewer than the preset's; the faces and the drawn voxels keep what the
// preset's paths give them. The lump's 8 voxels take a few hundred steps per path: FINAL's cheap 1024 first.
TEST(GatheringPlan, ASmallScenesPathsRiseWithinItsTracedWork) {
    const bake::GatheringPlan cheap = bake::planGathering(smallLump(), preset(256, 1024), lumpVoxels(), 1);
    ASSERT_EQ(cheap.paths, 1024);
    const double perPath = cheap.steps / cheap.paths;  // all the voxels' steps for one path each (the same pilot)
    ASSERT_GT(bake::kSmallSceneTracedSteps / perPath, 2.0 * cheap.paths);
    const bake::GatheringPlan raised =
        bake::planGathering(smallLump(), preset(256, 1024, bake::kSmallSceneTracedSteps), lumpVoxels(), 1);
    EXPECT_EQ(raised.paths, std::min(int(bake::kSmallSceneTracedSteps / perPath), bake::kMostTracedShare * 1024));
    EXPECT_DOUBLE_EQ(raised.steps, perPath * raised.paths);
    EXPECT_LE(raised.steps, bake::kSmallSceneTracedSteps);
    EXPECT_EQ(raised.drawnPaths, raised.paths);
    EXPECT_EQ(raised.facePaths, cheap.facePaths);
    EXPECT_EQ(raised.litFacePaths, cheap.litFacePaths);
    // The traced work the raise leaves goes to the faces (gatheredVoxelFaces); none raised, all of it.
    EXPECT_DOUBLE_EQ(raised.smallSceneSteps, bake::kSmallSceneTracedSteps - perPath * (raised.paths - cheap.paths));
    EXPECT_DOUBLE_EQ(cheap.smallSceneSteps, 0.0);
    const bake::GatheringPlan unraised =
        bake::planGathering(smallLump(), preset(256, 1024, perPath * 100.0), lumpVoxels(), 1);
    EXPECT_DOUBLE_EQ(unraised.smallSceneSteps, perPath * 100.0);
    // Less traced work: fewer paths (any count), never fewer than the preset's.
    EXPECT_EQ(bake::planGathering(smallLump(), preset(256, 1024, perPath * 3000.5), lumpVoxels(), 1).paths, 3000);
    EXPECT_EQ(bake::planGathering(smallLump(), preset(256, 1024, perPath * 100.0), lumpVoxels(), 1).paths, 1024);
}

// Where light tracing took a small scene's traced work (layerFaces), the plan is the preset's, as in a scene whose
// preset has none: the lump's raise above is not taken twice.
TEST(GatheringPlan, ASmallScenesWorkTakenByLightTracingRaisesNothing) {
    const bake::GatheringPlan none = bake::planGathering(smallLump(), preset(256, 1024), lumpVoxels(), 1);
    const bake::GatheringPlan taken = bake::planGathering(smallLump(), preset(256, 1024, bake::kSmallSceneTracedSteps),
                                                          lumpVoxels(), 1, bake::SmallSceneWork::TakenByLightTracing);
    ASSERT_EQ(none.paths, 1024);
    EXPECT_EQ(taken.paths, none.paths);
    EXPECT_EQ(taken.drawnPaths, none.drawnPaths);
    EXPECT_DOUBLE_EQ(taken.steps, none.steps);
    EXPECT_DOUBLE_EQ(taken.smallSceneSteps, 0.0);
}

// A large scene's traced voxels keep the preset's paths: the traced work shrinks inversely as its snow voxels pass
// kSmallSceneVoxels (a 100^3 block of snow: a tenth of it, 1e7 steps, under what 1024 paths of its corner's 1000 voxels
// cost, which the whole 1e8 would raise).
TEST(GatheringPlan, ALargeScenesPathsStayThePresets) {
    const openvdb::CoordBBox block(openvdb::Coord(0), openvdb::Coord(99));
    const Scene large = test::boxScene(block, 1.0f, VolumeOptics{10.0, Rgb(0.999), 0.85}, glm::dvec3(0.0, 0.0, 1.0));
    ASSERT_EQ(large.medium->density().activeVoxelCount(), 1000000);
    std::vector<openvdb::Coord> corner;
    for (const openvdb::Coord &c : openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(9))) corner.push_back(c);
    const bake::GatheringPlan cheap = bake::planGathering(large, preset(256, 1024), corner, 1);
    ASSERT_EQ(cheap.paths, 1024);
    ASSERT_GT(cheap.steps, 0.1 * bake::kSmallSceneTracedSteps);
    ASSERT_LT(cheap.steps, 0.5 * bake::kSmallSceneTracedSteps);
    const bake::GatheringPlan final =
        bake::planGathering(large, preset(256, 1024, bake::kSmallSceneTracedSteps), corner, 1);
    EXPECT_EQ(final.paths, 1024);
    EXPECT_DOUBLE_EQ(final.smallSceneSteps, 0.1 * bake::kSmallSceneTracedSteps);
}

// The same scene and seed plan the same paths (planGathering's pilot is seeded): the bake stays deterministic.
TEST(GatheringPlan, ASmallScenesPlanIsTheSameForTheSameSeed) {
    const bake::Preset final = preset(256, 1024, bake::kSmallSceneTracedSteps);
    const auto plan = [&] { return bake::planGathering(smallLump(), final, lumpVoxels(), 7); };
    const bake::GatheringPlan a = plan(), b = plan();
    EXPECT_GT(a.paths, 1024);
    EXPECT_EQ(a.paths, b.paths);
    EXPECT_DOUBLE_EQ(a.steps, b.steps);
}

}  // namespace firn
