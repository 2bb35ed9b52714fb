#include "firn/snow/snow_layer.h"

#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>
#include <tbb/global_control.h>

#include "firn/util/error.h"
#include "test_geometry.h"

namespace firn {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Height (m) of the snow surface above (x, y): the highest sign change of the level set, scanning down.
double snowTopAt(const SnowGrids &grids, double x, double y, double zHigh = 3.0, double zLow = -1.0) {
    const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sdf(*grids.surface);
    const double step = 0.25 * grids.surface->voxelSize()[0];
    double previous = sdf.wsSample(openvdb::Vec3d(x, y, zHigh));
    for (double z = zHigh - step; z > zLow; z -= step) {
        const double value = sdf.wsSample(openvdb::Vec3d(x, y, z));
        if (previous > 0.0 && value <= 0.0) return z + step * value / (value - previous);
        previous = value;
    }
    return std::nan("");
}

double densityAt(const SnowGrids &grids, double x, double y, double z) {
    const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> rho(*grids.density);
    return rho.wsSample(openvdb::Vec3d(x, y, z));
}

SnowLayer generate(const TriangleMesh &targets, const TriangleMesh &occluders, SnowLayerSettings s = {}) {
    return generateSnowLayer(targets, occluders, s, nullptr);
}

}  // namespace

TEST(SnowLayer, TopOfOpenFlatSnowIsAtTheRequestedDepth) {
    SnowLayerSettings s;
    s.depth = 0.1;
    s.randomness = 0.5;
    const SnowLayer layer = generate(test::plane(2.0f), {}, s);
    double sum = 0.0;
    int n = 0;
    for (double x = -0.6; x <= 0.6; x += 0.06)
        for (double y = -0.6; y <= 0.6; y += 0.06) {
            const double top = snowTopAt(layer.grids, x, y);
            ASSERT_FALSE(std::isnan(top)) << "no snow at " << x << ", " << y;
            sum += top, ++n;
        }
    EXPECT_NEAR(sum / n, s.depth, 0.1 * s.depth);  // issue: within +-10 % on average
}

TEST(SnowLayer, DensityGrowsWithDepth) {
    SnowLayerSettings s;
    s.depth = 0.2;
    s.densityTop = 100.0, s.densityBottom = 400.0, s.compaction = 0.6;
    const SnowLayer layer = generate(test::plane(1.5f), {}, s);
    double previous = 1e9;
    for (double z = 0.01; z < 0.17; z += 0.03) {
        double mean = 0.0;
        for (double x = -0.3; x <= 0.3; x += 0.05) mean += densityAt(layer.grids, x, 0.1, z) / 13.0;
        EXPECT_LT(mean, previous) << "at z = " << z;
        EXPECT_GT(mean, 99.0);
        previous = mean;
    }
}

TEST(SnowLayer, NoSnowUnderATableButFullDepthBesideIt) {
    const TriangleMesh ground = test::plane(4.0f);
    const TriangleMesh tableTop = test::box({-0.5f, -0.5f, 0.7f}, {0.5f, 0.5f, 0.75f});
    SnowLayerSettings s;
    const SnowLayer layer = generate(ground, tableTop, s);
    // The snowfall cone (15 deg) leaves the ground fully hidden up to 0.7 m x tan(15 deg) = 0.19 m inside the
    // top's edge; snow at the edge of that shadow reaches one metaball radius (0.094 m) further in.
    for (double x = -0.2; x <= 0.2; x += 0.04)
        for (double y = -0.2; y <= 0.2; y += 0.04)
            for (double z = 0.0; z < 0.2; z += 0.02) EXPECT_EQ(densityAt(layer.grids, x, y, z), 0.0);
    double beside = 0.0;
    for (double y = -0.5; y <= 0.5; y += 0.1) beside += snowTopAt(layer.grids, 1.4, y) / 11.0;
    EXPECT_NEAR(beside, s.depth, 0.1 * s.depth);
}

TEST(SnowLayer, TableTopGetsSnowOnTopOnly) {
    const TriangleMesh tableTop = test::box({-0.5f, -0.5f, 0.7f}, {0.5f, 0.5f, 0.75f});
    const SnowLayer layer = generate(tableTop, {}, {});
    EXPECT_NEAR(snowTopAt(layer.grids, 0.0, 0.0), 0.75 + 0.1, 0.02);
    EXPECT_EQ(densityAt(layer.grids, 0.0, 0.0, 0.72), 0.0);  // inside the board
    EXPECT_EQ(densityAt(layer.grids, 0.0, 0.0, 0.65), 0.0);  // under it
}

TEST(SnowLayer, SlopesSteeperThanTheMaximumStayBare) {
    SnowLayerSettings s;
    s.maxSlope = 60.0 * kDeg;
    EXPECT_THROW(generate(test::plane(1.0f, {}, float(75.0 * kDeg)), {}, s), InvalidArgument);
    const SnowLayer layer = generate(test::plane(1.0f, {}, float(30.0 * kDeg)), {}, s);
    EXPECT_GT(layer.siteCount, 100u);
    // The snowfall on a slope spreads over more surface: depth along the normal is depth * cos(slope),
    // measured here along the vertical through the centre: depth * cos / cos = depth above the plane.
    EXPECT_NEAR(snowTopAt(layer.grids, 0.0, 0.0), s.depth, 0.15 * s.depth);
}

TEST(SnowLayer, SphereGetsACapOnTopAndNothingInside) {
    const glm::vec3 centre(0.0f, 0.0f, 0.5f);
    const float radius = 0.5f;
    const SnowLayer layer = generate(test::sphere(centre, radius), {}, {});
    EXPECT_NEAR(snowTopAt(layer.grids, 0.0, 0.0), 1.0 + 0.1, 0.015);
    const double h = layer.voxelSize;
    for (auto it = layer.grids.density->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d p = layer.grids.density->indexToWorld(it.getCoord());
        const double r = (p - openvdb::Vec3d(centre.x, centre.y, centre.z)).length();
        ASSERT_GT(p.z(), centre.z) << "snow below the equator";
        ASSERT_GT(r, radius - 1.5 * h) << "snow inside the sphere";
    }
}

TEST(SnowLayer, SameSeedSameGridWhateverTheThreadCount) {
    SnowLayerSettings s;
    s.seed = 7;
    const TriangleMesh ground = test::plane(1.0f);
    const SnowLayer a = generate(ground, {}, s);
    SnowLayer b;
    {
        tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
        b = generate(ground, {}, s);
    }
    ASSERT_EQ(a.grids.density->activeVoxelCount(), b.grids.density->activeVoxelCount());
    auto bAcc = b.grids.density->getConstAccessor();
    for (auto it = a.grids.density->cbeginValueOn(); it; ++it) ASSERT_EQ(*it, bAcc.getValue(it.getCoord()));
    s.seed = 8;
    const SnowLayer c = generate(ground, {}, s);
    EXPECT_NE(c.grids.density->activeVoxelCount(), a.grids.density->activeVoxelCount());
}

TEST(SnowLayer, KeptMetaballsRebuildTheSameGrids) {
    SnowLayerSettings s;
    const SnowLayer layer = generate(test::plane(1.0f), {}, s);
    const SnowGrids again = rasterizeSnow(layer.metaballs, s.raster(), SubProgress(nullptr, 0, 1));
    ASSERT_EQ(again.density->activeVoxelCount(), layer.grids.density->activeVoxelCount());
    auto acc = again.density->getConstAccessor();
    for (auto it = layer.grids.density->cbeginValueOn(); it; ++it) ASSERT_EQ(*it, acc.getValue(it.getCoord()));
}

TEST(SnowLayer, VoxelBudgetIsCheckedBeforeAllocating) {
    SnowLayerSettings s;
    s.voxelSize = 0.001;
    s.maxVoxels = 1e6;
    try {
        generate(test::plane(10.0f), {}, s);
        FAIL() << "expected BudgetExceeded";
    } catch (const BudgetExceeded &e) {
        EXPECT_NE(std::string(e.what()).find("voxel size of at least"), std::string::npos) << e.what();
    }
}

// Fuzzing (issue 11): a huge target with a fine spacing asked for 1e12 landing sites and threw std::bad_alloc.
TEST(SnowLayer, LandingSiteCountIsCheckedBeforePlacingThem) {
    SnowLayerSettings s;
    s.spacing = 0.01;
    s.voxelSize = 0.05;
    s.maxVoxels = 1e11;  // the snow's volume alone (8e10 voxels) fits: the sites (1e12) do not
    try {
        generate(test::plane(1e4f), {}, s);
        FAIL() << "expected BudgetExceeded";
    } catch (const BudgetExceeded &e) {
        EXPECT_NE(std::string(e.what()).find("larger spacing"), std::string::npos) << e.what();
    }
}

// Fuzzing: kept metaballs come back from the user; nonsense in them is refused, not rasterized.
TEST(SnowLayer, EditedMetaballsAreCheckedBeforeRasterizing) {
    SnowLayerSettings s;
    s.maxVoxels = 1e6;
    const SnowLayer layer = generate(test::plane(0.5f), {}, s);
    const auto rebuild = [&](auto edit) {
        std::vector<Metaball> balls = layer.metaballs;
        edit(balls.back());
        return rasterizeSnow(balls, s.raster(), SubProgress(nullptr, 0, 1));
    };
    EXPECT_THROW(rebuild([](Metaball &b) { b.centre.x = std::nanf(""); }), InvalidArgument);
    EXPECT_THROW(rebuild([](Metaball &b) { b.depth = INFINITY; }), InvalidArgument);
    EXPECT_THROW(rebuild([](Metaball &b) { b.radius = 0.0f; }), InvalidArgument);
    EXPECT_THROW(rebuild([](Metaball &b) { b.radius = 1e30f; }), InvalidArgument);     // int overflow of its leaves
    EXPECT_THROW(rebuild([](Metaball &b) { b.centre.y = 1e6f; }), InvalidArgument);    // beyond the leaf keys
    EXPECT_THROW(rebuild([](Metaball &b) { b.radius = 100.0f; }), BudgetExceeded);     // 1e10 leaf pairs
    // A base 1e30 m below the ball (UBSan: float-to-int overflow) leaves the ball out, nothing else.
    const SnowGrids sunk = rebuild([](Metaball &b) { b.base = -1e30f; });
    EXPECT_LE(sunk.density->activeVoxelCount(), layer.grids.density->activeVoxelCount());
}

TEST(SnowLayer, BadSettingsAreRejectedWithTheirName) {
    const TriangleMesh ground = test::plane(1.0f);
    auto expectMessage = [&](SnowLayerSettings s, const std::string &name) {
        try {
            generate(ground, {}, s);
            FAIL() << "expected InvalidArgument for " << name;
        } catch (const InvalidArgument &e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    };
    SnowLayerSettings s;
    s.depth = -1.0;
    expectMessage(s, "depth");
    s = {};
    s.depth = 1e6;
    expectMessage(s, "depth");
    s = {};
    s.direction = {0.0f, 0.0f, 1.0f};
    expectMessage(s, "direction");
    s = {};
    s.voxelSize = 0.5;
    expectMessage(s, "voxel size");
    s = {};
    s.densityBottom = 2000.0;
    expectMessage(s, "bottom density");
    EXPECT_THROW(generate(TriangleMesh{}, {}, {}), InvalidArgument);
}

TEST(SnowLayer, WindTiltedSnowfallLeavesTheLeeOfAWallBare) {
    // A wall along y at x = 0; wind blows snow towards +x, so the lee (x > 0) close to the wall stays bare.
    const TriangleMesh ground = test::plane(4.0f);
    const TriangleMesh wall = test::box({-0.05f, -2.0f, 0.0f}, {0.05f, 2.0f, 1.0f});
    SnowLayerSettings s;
    s.direction = glm::normalize(glm::vec3(1.0f, 0.0f, -1.0f));  // 45 deg wind
    s.spread = 5.0 * kDeg;
    const SnowLayer layer = generate(ground, wall, s);
    EXPECT_EQ(densityAt(layer.grids, 0.4, 0.0, 0.03), 0.0);          // in the lee
    EXPECT_GT(densityAt(layer.grids, -0.4, 0.0, 0.03), 50.0);        // windward
    EXPECT_GT(densityAt(layer.grids, 1.6, 0.0, 0.03), 50.0);         // lee, beyond the wall's shadow
}

}  // namespace firn
