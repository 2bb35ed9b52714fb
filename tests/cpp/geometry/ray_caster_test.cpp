#include "firn/geometry/ray_caster.h"

#include <atomic>

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

namespace firn {

namespace {
// A unit square at z = 1 (two triangles, normal +z) and nothing else.
TriangleMesh square() {
    const float v[] = {0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
    const unsigned t[] = {0, 1, 2, 0, 2, 3};
    return makeTriangleMesh(v, 4, t, 2);
}
}  // namespace

TEST(RayCaster, HitsReportDistanceTriangleAndNormal) {
    const RayCaster caster(square());
    const auto hit = caster.intersect({0.25f, 0.75f, 0.0f}, {0.0f, 0.0f, 1.0f});
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->distance, 1.0f, 1e-6f);
    EXPECT_EQ(hit->triangle, 1u);  // (0.25, 0.75) lies in the second triangle
    EXPECT_NEAR(hit->normal.z, 1.0f, 1e-6f);
    EXPECT_FALSE(caster.intersect({2.0f, 2.0f, 0.0f}, {0.0f, 0.0f, 1.0f}));
}

TEST(RayCaster, OccludedHonoursTheSegment) {
    const RayCaster caster(square());
    EXPECT_TRUE(caster.occluded({0.5f, 0.5f, 0.0f}, {0.0f, 0.0f, 1.0f}));
    EXPECT_FALSE(caster.occluded({0.5f, 0.5f, 0.0f}, {0.0f, 0.0f, 1.0f}, 0.0f, 0.9f));   // stops short
    EXPECT_FALSE(caster.occluded({0.5f, 0.5f, 0.0f}, {0.0f, 0.0f, 1.0f}, 1.1f));         // starts beyond
    EXPECT_FALSE(caster.occluded({0.5f, 0.5f, 2.0f}, {0.0f, 0.0f, 1.0f}));               // points away
}

TEST(RayCaster, EmptySceneNeverHits) {
    const RayCaster caster(TriangleMesh{});
    EXPECT_TRUE(caster.empty());
    EXPECT_FALSE(caster.occluded({0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}));
    EXPECT_FALSE(caster.intersect({0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}));
}

TEST(RayCaster, ConcurrentQueriesAgree) {
    const RayCaster caster(square());
    std::atomic<int> hits{0};
    tbb::parallel_for(0, 10000, [&](int i) {
        const float x = (i % 100 + 0.5f) / 50.0f - 0.5f;  // half the rays miss the square
        hits += caster.occluded({x, 0.5f, 0.0f}, {0.0f, 0.0f, 1.0f});
    });
    EXPECT_EQ(hits.load(), 5000);
}

}  // namespace firn
