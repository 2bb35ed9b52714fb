#include "firn/geometry/ray_caster.h"

#include <atomic>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include "firn/geometry/box_triangle.h"
#include "test_geometry.h"

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

// The box query finds exactly the triangles the separating-axis test finds among all of them (oracle: that test on
// every triangle of a sphere of 4096), for boxes of a voxel's size and smaller about and across its surface.
TEST(RayCaster, TrianglesInBoxAreThoseOverlappingIt) {
    const TriangleMesh sphere = test::sphere({0.1f, 0.2f, 0.3f}, 0.05f);
    const RayCaster caster(sphere);
    int found = 0;
    for (int i = 0; i < 200; ++i) {
        const double size = 0.002 + 0.00005 * i;  // m
        const double z = 1.0 - (2.0 * i + 1.0) / 200.0, phi = 2.399963 * i;  // a Fibonacci sphere's directions
        const glm::dvec3 d(std::sqrt(1.0 - z * z) * std::cos(phi), std::sqrt(1.0 - z * z) * std::sin(phi), z);
        const glm::dvec3 lo = glm::dvec3(0.1, 0.2, 0.3) + (0.05 + 0.001 * (i % 5 - 2)) * d - 0.5 * size;
        const glm::dvec3 hi = lo + size;
        std::vector<unsigned> expected;
        for (unsigned t = 0; t < sphere.triangleCount(); ++t)
            if (triangleOverlapsBox(lo, hi, sphere.vertex(t, 0), sphere.vertex(t, 1), sphere.vertex(t, 2)))
                expected.push_back(t);
        EXPECT_EQ(caster.trianglesInBox(lo, hi), expected) << "box " << i;
        found += int(expected.size());
    }
    EXPECT_GT(found, 200);  // the boxes meet the surface
}

}  // namespace firn
