#include "firn/snow/snow_brush.h"

#include <cmath>

#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>

#include "firn/util/error.h"
#include "test_geometry.h"

namespace firn {

namespace {

// Height (m) of the snow surface above (x, y): the highest sign change of the level set, scanning down; 0 without
// snow there.
double snowTopAt(const SnowGrids &grids, double x, double y) {
    const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sdf(*grids.surface);
    const double step = 0.25 * grids.surface->voxelSize()[0];
    double previous = sdf.wsSample(openvdb::Vec3d(x, y, 2.0));
    for (double z = 2.0 - step; z > -0.5; z -= step) {
        const double value = sdf.wsSample(openvdb::Vec3d(x, y, z));
        if (previous > 0.0 && value <= 0.0) return z + step * value / (value - previous);
        previous = value;
    }
    return 0.0;
}

// Every voxel of `a` (value and active state) is the same in `b`, and the other way round.
void expectSameGrid(const openvdb::FloatGrid &a, const openvdb::FloatGrid &b) {
    EXPECT_EQ(a.activeVoxelCount(), b.activeVoxelCount());
    const auto compare = [](const openvdb::FloatGrid &x, const openvdb::FloatGrid &y) {
        auto other = y.getConstAccessor();
        int mismatches = 0;
        for (auto it = x.cbeginValueOn(); it; ++it)
            if (other.getValue(it.getCoord()) != *it || !other.isValueOn(it.getCoord())) ++mismatches;
        return mismatches;
    };
    EXPECT_EQ(compare(a, b), 0);
    EXPECT_EQ(compare(b, a), 0);
}

struct Scene {
    TriangleMesh ground = test::plane(4.0f);
    TriangleMesh table = test::box({-0.5f, -0.5f, 0.7f}, {0.5f, 0.5f, 0.75f});
    SnowLayerSettings settings;
    SnowLayer layer;
    Scene() {
        settings.depth = 0.1;
        layer = generateSnowLayer(ground, table, settings, nullptr);
    }
    SnowCanvas canvas() const { return SnowCanvas(layer.metaballs, layer.grids, settings, ground, table); }
};

Dab dabAt(glm::vec3 centre, BrushMode mode, double strength = 0.1, double radius = 0.3) {
    Dab d;
    d.centre = centre, d.mode = mode, d.strength = strength, d.radius = radius;
    return d;
}

}  // namespace

TEST(SnowBrush, DabsKeepTheGridsWhatAFullRasterizationOfTheBallsMakes) {
    Scene scene;
    // The canvas edits its grids in place: give it a copy, to compare with the layer's.
    SnowGrids copy{scene.layer.grids.density->deepCopy(), scene.layer.grids.surface->deepCopy()};
    SnowCanvas canvas(scene.layer.metaballs, copy, scene.settings, scene.ground, scene.table);
    for (float x = 0.8f; x < 1.6f; x += 0.1f) canvas.apply(dabAt({x, 0.2f, 0.1f}, BrushMode::Add, 0.05));
    canvas.apply(dabAt({1.2f, -0.5f, 0.1f}, BrushMode::Erase, 0.05));
    canvas.apply(dabAt({1.0f, 0.2f, 0.2f}, BrushMode::Smooth, 0.05));
    ASSERT_NE(canvas.metaballs().size(), scene.layer.metaballs.size());  // the dabs changed the snow
    const SnowGrids full = rasterizeSnow(canvas.metaballs(), scene.settings.raster(), SubProgress(nullptr, 0, 1));
    expectSameGrid(*canvas.grids().density, *full.density);
    expectSameGrid(*canvas.grids().surface, *full.surface);
}

TEST(SnowBrush, AddPutsSnowUnderTheBrushOnly) {
    Scene scene;
    SnowCanvas canvas = scene.canvas();
    const double before = snowTopAt(canvas.grids(), 1.2, 0.0), far = snowTopAt(canvas.grids(), -1.2, 0.0);
    for (int i = 0; i < 4; ++i) EXPECT_GT(canvas.apply(dabAt({1.2f, 0.0f, 0.1f}, BrushMode::Add, 0.05)).added, 0u);
    // Four dabs of 5 cm at the centre: the top rises by about that much (stacked columns overlap: more, not less).
    EXPECT_GT(snowTopAt(canvas.grids(), 1.2, 0.0), before + 0.1);
    EXPECT_EQ(snowTopAt(canvas.grids(), -1.2, 0.0), far);
    EXPECT_NEAR(snowTopAt(canvas.grids(), 1.2, 0.6), before, 0.01);  // beyond the radius (0.3 m) and a ball
}

TEST(SnowBrush, ADabRaisesTheSnowAtItsCentreByItsStrength) {
    // Strength is the depth a dab adds at the brush's centre: the new columns' layout puts their own iso-surface
    // that far above the snow they stand on (metaball_layout.h); the old snow's field adds a little above it.
    Scene scene;
    SnowCanvas canvas = scene.canvas();
    const auto meanTop = [&] {
        double sum = 0.0;
        for (double dx : {-0.02, 0.0, 0.02})
            for (double dy : {-0.02, 0.0, 0.02}) sum += snowTopAt(canvas.grids(), 1.2 + dx, dy) / 9.0;
        return sum;
    };
    const double before = meanTop();
    canvas.apply(dabAt({1.2f, 0.0f, 0.1f}, BrushMode::Add, 0.05));
    EXPECT_NEAR(meanTop() - before, 0.05, 0.0125);
}

TEST(SnowBrush, AddUnderATableLandsNothing) {
    Scene scene;
    SnowCanvas canvas = scene.canvas();
    const DabStats stats = canvas.apply(dabAt({0.0f, 0.0f, 0.0f}, BrushMode::Add, 0.1, 0.2));
    EXPECT_EQ(stats.added, 0u);
    EXPECT_EQ(snowTopAt(canvas.grids(), 0.0, 0.0), 0.0);
}

TEST(SnowBrush, EraseRemovesTheSnowUnderTheBrush) {
    Scene scene;
    SnowCanvas canvas = scene.canvas();
    ASSERT_GT(snowTopAt(canvas.grids(), 1.2, 0.0), 0.05);
    const DabStats stats = canvas.apply(dabAt({1.2f, 0.0f, 0.1f}, BrushMode::Erase, 1.0));
    EXPECT_GT(stats.removed, 0u);
    EXPECT_EQ(snowTopAt(canvas.grids(), 1.2, 0.0), 0.0);
    EXPECT_GT(snowTopAt(canvas.grids(), -1.2, 0.0), 0.05);
}

TEST(SnowBrush, SmoothLowersAPeak) {
    Scene scene;
    SnowCanvas canvas = scene.canvas();
    canvas.apply(dabAt({1.2f, 0.0f, 0.1f}, BrushMode::Add, 0.1, 0.1));
    const double peak = snowTopAt(canvas.grids(), 1.2, 0.0);
    for (int i = 0; i < 5; ++i) canvas.apply(dabAt({1.2f, 0.0f, 0.2f}, BrushMode::Smooth, 0.02, 0.4));
    EXPECT_LT(snowTopAt(canvas.grids(), 1.2, 0.0), peak - 0.02);
}

TEST(SnowBrush, RefusesBadDabs) {
    Scene scene;
    SnowCanvas canvas = scene.canvas();
    EXPECT_THROW(canvas.apply(dabAt({NAN, 0, 0}, BrushMode::Add)), InvalidArgument);
    EXPECT_THROW(canvas.apply(dabAt({0, 0, 0}, BrushMode::Add, 0.1, -1.0)), InvalidArgument);
    EXPECT_THROW(canvas.apply(dabAt({0, 0, 0}, BrushMode::Add, 0.1, 500.0)), BudgetExceeded);
}

}  // namespace firn
