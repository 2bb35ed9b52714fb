// The early voxel bound (snow_volume_bound.h): never above what the snow really needs (so it never refuses snow
// that fits), close enough to refuse large planes at once, and sheltered area left out.
#include "firn/snow/snow_volume_bound.h"

#include <string>

#include <gtest/gtest.h>

#include "firn/geometry/ray_caster.h"
#include "firn/snow/snow_layer.h"
#include "firn/util/error.h"
#include "test_geometry.h"

namespace firn {

namespace {

double bound(const TriangleMesh &targets, const TriangleMesh &shelter, const SnowLayerSettings &s) {
    return snowVoxelLowerBound(targets, RayCaster(merge({targets, shelter})), s.snowfall(), s.depth,
                               s.effectiveVoxelSize());
}

double activeVoxels(const TriangleMesh &targets, const TriangleMesh &occluders, const SnowLayerSettings &s) {
    return double(generateSnowLayer(targets, occluders, s, nullptr).grids.density->activeVoxelCount());
}

}  // namespace

// Below the real count and within a factor of 4 of it: an open plane, a slope, a plane half under a roof.
TEST(SnowVolumeBound, BelowTheSnowsVoxelsAndNearThem) {
    SnowLayerSettings s;
    s.voxelSize = 0.02;
    const TriangleMesh roof = test::plane(1.0f, {0.5f, 0.0f, 0.6f});
    struct Case {
        TriangleMesh targets, occluders;
    };
    for (const Case &c : {Case{test::plane(2.0f), {}}, Case{test::plane(2.0f, {0, 0, 0}, 0.5f), {}},
                          Case{test::plane(2.0f), roof}}) {
        const double lower = bound(c.targets, c.occluders, s), actual = activeVoxels(c.targets, c.occluders, s);
        EXPECT_LE(lower, actual);
        EXPECT_GT(lower, actual / 4.0);
    }
}

TEST(SnowVolumeBound, TheRoofsShelterIsLeftOut) {
    SnowLayerSettings s;
    s.voxelSize = 0.02;
    const double open = bound(test::plane(2.0f), {}, s);
    const double halfCovered = bound(test::plane(2.0f), test::plane(1.0f, {0.5f, 0.0f, 0.6f}), s);
    EXPECT_NEAR(halfCovered / open, 0.75, 0.1);  // a quarter of the plane lies under the 1 m roof
    EXPECT_EQ(bound(test::plane(2.0f), test::plane(3.0f, {0, 0, 0.5f}), s), 0.0);  // all of it under a roof
}

// A 200 m plane at the default 1 cm voxels is refused by the bound, before a site is placed (that took a minute).
TEST(SnowVolumeBound, LargePlaneRefusedBeforeAnySite) {
    try {
        generateSnowLayer(test::plane(200.0f), {}, SnowLayerSettings{}, nullptr);
        FAIL() << "a 200 m plane at 1 cm fits no budget";
    } catch (const BudgetExceeded &error) {
        EXPECT_NE(std::string(error.what()).find("needs at least"), std::string::npos) << error.what();
    }
}

}  // namespace firn
