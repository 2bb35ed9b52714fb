// Tracks: the groove an emitter cuts is its swept box, and the snow it held is compacted underneath.
#include <cmath>

#include <gtest/gtest.h>
#include <openvdb/tools/Composite.h>

#include "firn/spray/tracks.h"
#include "firn/util/error.h"
#include "slab_snow.h"

namespace firn {
namespace {

constexpr double kH = 0.01;  // m, voxel

// The emitter: 0.4 m x 0.1 m, horizontal, its rectangle 5 cm under the snow's top, sliding 0.6 m along x.
std::vector<EmitterRectangle> slide() {
    std::vector<EmitterRectangle> positions;
    for (int k = 0; k <= 4; ++k)
        positions.push_back({{-0.3 + 0.15 * k, 0.0, -0.05}, {0.2, 0.0, 0.0}, {0.0, 0.05, 0.0}});
    return positions;
}

double totalMass(const SnowGrids &snow) {
    double sum = 0.0;
    for (auto it = snow.density->cbeginValueOn(); it; ++it) sum += *it;
    return sum * kH * kH * kH;  // kg
}

// The groove slide() cuts: x in [-0.5, 0.5], y in [-0.05, 0.05], from z = -0.05 - thickness = -0.07 up through
// the top at z = 0 (voxel-exact, +-1 voxel).
void expectSlideGroove(const openvdb::FloatGrid &phi) {
    // Depth: along the groove's axis the level set turns negative at its bottom.
    for (double x : {-0.4, 0.0, 0.4}) {
        double bottom = 0.05;
        while (test::levelSetAt(phi, x, 0.0, bottom) > 0.0) bottom -= 0.1 * kH;
        EXPECT_NEAR(bottom, -0.07, kH) << "x = " << x;
    }
    // Width: across the groove halfway down, the walls stand at y = +-0.05.
    for (double side : {-1.0, 1.0}) {
        double y = 0.0;
        while (test::levelSetAt(phi, 0.0, y, -0.035) > 0.0) y += side * 0.1 * kH;
        EXPECT_NEAR(std::abs(y), 0.05, kH) << side;
    }
    // Length: the groove ends where the emitter's ends went.
    double end = 0.0;
    while (test::levelSetAt(phi, end, 0.0, -0.035) > 0.0) end += 0.1 * kH;
    EXPECT_NEAR(end, 0.5, kH);
    // Untouched beside it.
    EXPECT_LT(test::levelSetAt(phi, 0.0, 0.15, -0.035), 0.0);
}

TEST(Tracks, TheGrooveIsTheSweptBoxAndItsSnowIsCompactedBelow) {
    SnowGrids snow = test::slabSnow({-0.8, -0.3, -0.3}, {0.8, 0.3, 0.0}, kH, 300.0f);
    const double massBefore = totalMass(snow);
    TrackSettings s;
    s.thickness = 0.02;
    s.compactionDepth = 0.05;
    const TrackStats stats = carveTrack(snow, slide(), {0.0, 0.0, -1.0}, s, 50e6);
    ASSERT_GT(stats.carvedVoxels, 0u);
    expectSlideGroove(*snow.surface);

    // The removed mass: 300 kg/m^3 x (1.0 m x 0.1 m x 0.07 m), up to the voxel ramp; all of it compacted below.
    EXPECT_NEAR(stats.removedMass, 300.0 * 1.0 * 0.1 * 0.07, 0.1 * 300.0 * 1.0 * 0.1 * 0.07);
    EXPECT_NEAR(stats.compactedMass, stats.removedMass, 1e-6 * stats.removedMass);
    EXPECT_NEAR(totalMass(snow), massBefore, 1e-4 * massBefore);
    auto rho = snow.density->getConstAccessor();
    const auto at = [&](double x, double y, double z) {
        return rho.getValue(openvdb::Coord::round(snow.density->worldToIndex(openvdb::Vec3d(x, y, z))));
    };
    EXPECT_EQ(at(0.0, 0.0, -0.03), 0.0f);   // the groove is empty
    EXPECT_GT(at(0.0, 0.0, -0.10), 400.0f);  // the layer below holds its snow: 300 + 2.1 kg / 0.005 m^3 = 720
    EXPECT_FLOAT_EQ(at(0.0, 0.0, -0.20), 300.0f);  // deeper, untouched
    EXPECT_FLOAT_EQ(at(0.0, 0.2, -0.10), 300.0f);  // beside, untouched
}

// A box rises above the snow over its own rectangle, not above the scene's highest snow: beside the slab stands a
// block 2 m tall (a slope's upper part). Raised to that block's top, the boxes' bounds hold about 620,000 voxels;
// raised above the slab, about 74,000. Under a budget of 200,000 the groove is cut, and it is the slab's groove.
TEST(Tracks, EachBoxRisesAboveTheSnowOverItNotAboveTheHighestSnow) {
    SnowGrids snow = test::slabSnow({-0.8, -0.3, -0.3}, {0.8, 0.3, 0.0}, kH, 300.0f);
    const SnowGrids block = test::slabSnow({1.0, -0.3, -0.3}, {1.2, 0.3, 2.0}, kH, 300.0f);
    openvdb::tools::csgUnion(*snow.surface, *block.surface->deepCopy());
    TrackSettings s;
    s.thickness = 0.02;
    s.compactionDepth = 0.05;
    ASSERT_NO_THROW(carveTrack(snow, slide(), {0.0, 0.0, -1.0}, s, 200e3));
    expectSlideGroove(*snow.surface);
}

// An emitter turned half round about its normal from one position to the next: the positions added between them
// pass through a rectangle of no area (the corners interpolated straight), which has no normal. It sweeps nothing;
// the groove is the two ends' boxes and what lies between them, the level set finite.
TEST(Tracks, AnEmitterTurnedHalfRoundBetweenPositionsCutsAFiniteGroove) {
    SnowGrids snow = test::slabSnow({-0.8, -0.3, -0.3}, {0.8, 0.3, 0.0}, kH, 300.0f);
    const std::vector<EmitterRectangle> turned{{{-0.3, 0.0, -0.05}, {0.2, 0.0, 0.0}, {0.0, 0.05, 0.0}},
                                               {{0.3, 0.0, -0.05}, {-0.2, 0.0, 0.0}, {0.0, -0.05, 0.0}}};
    const TrackStats stats = carveTrack(snow, turned, {0.0, 0.0, -1.0}, TrackSettings{}, 50e6);
    EXPECT_GT(stats.carvedVoxels, 0u);
    EXPECT_TRUE(std::isfinite(stats.removedMass));
    for (auto it = snow.surface->cbeginValueOn(); it; ++it) ASSERT_TRUE(std::isfinite(*it)) << it.getCoord();
    EXPECT_GT(test::levelSetAt(*snow.surface, -0.3, 0.0, -0.035), 0.0);  // both ends cut
    EXPECT_GT(test::levelSetAt(*snow.surface, 0.3, 0.0, -0.035), 0.0);
}

TEST(Tracks, AnEmitterAboveTheSnowLeavesItAlone) {
    SnowGrids snow = test::slabSnow({-0.5, -0.3, -0.3}, {0.5, 0.3, 0.0}, kH, 300.0f);
    std::vector<EmitterRectangle> high = slide();
    for (EmitterRectangle &r : high) r.centre.z = 0.2;
    EXPECT_EQ(carveTrack(snow, high, {0.0, 0.0, -1.0}, TrackSettings{}, 50e6).carvedVoxels, 0u);
}

TEST(Tracks, ATrackOverTheVoxelBudgetIsRefusedBeforeAllocating) {
    SnowGrids snow = test::slabSnow({-0.5, -0.3, -0.3}, {0.5, 0.3, 0.0}, kH, 300.0f);
    EXPECT_THROW(carveTrack(snow, slide(), {0.0, 0.0, -1.0}, TrackSettings{}, 1000.0), BudgetExceeded);
}

// Each position's box reaches up to the snow's top: an emitter 10 km under a 30 cm slab raises boxes 10 km tall,
// almost all of them outside the snow. OpenVDB fills the whole boxes, so the budget counts them whole: counted
// within the snow's bounds alone they passed it and took every byte of memory (tests/fuzz, spray).
TEST(Tracks, ATrackFarUnderTheSnowCountsItsWholeBoxesAgainstTheBudget) {
    SnowGrids snow = test::slabSnow({-0.5, -0.3, -0.3}, {0.5, 0.3, 0.0}, kH, 300.0f);
    std::vector<EmitterRectangle> deep = slide();
    for (EmitterRectangle &r : deep) r.centre.z = -1e4;
    EXPECT_THROW(carveTrack(snow, deep, {0.0, 0.0, -1.0}, TrackSettings{}, 50e6), BudgetExceeded);
}

TEST(Tracks, BadSettingsAreRefused) {
    TrackSettings s;
    s.thickness = 0.0;
    EXPECT_THROW(s.validate(), InvalidArgument);
    s = TrackSettings{};
    s.maxDensity = 1000.0;
    EXPECT_THROW(s.validate(), InvalidArgument);
}

}  // namespace
}  // namespace firn
