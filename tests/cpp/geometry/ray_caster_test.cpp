#include "firn/geometry/ray_caster.h"

#include <atomic>
#include <cmath>
#include <optional>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include "../test_geometry.h"

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

// The packets (rtcIntersect16) must give what one ray at a time gives, bit for bit: the bake's sky rays are traced
// as packets and its grids were measured with single rays. 37 rays per origin: two full packets and a part one;
// origins inside, outside and on a sphere's hull and a box around it, directions all round (about half meet nothing).
TEST(RayCaster, PacketsHitWhatSingleRaysHit) {
    std::vector<glm::vec3> points;
    std::vector<unsigned> indices;
    for (const TriangleMesh &part : {test::sphere({0.0f, 0.0f, 0.0f}, 1.0f, 24, 48),
                                     test::box({-1.5f, -1.5f, -1.5f}, {1.5f, 1.5f, 1.2f})}) {
        const auto base = unsigned(points.size());
        points.insert(points.end(), part.positions.begin(), part.positions.end());
        for (const glm::uvec3 &t : part.triangles) indices.insert(indices.end(), {base + t.x, base + t.y, base + t.z});
    }
    const RayCaster caster(test::meshOf(points, indices));
    constexpr int kRays = 37;
    int hits = 0, rays = 0;
    for (const glm::vec3 origin : {glm::vec3(0.1f, -0.2f, 0.3f), glm::vec3(1.2f, 0.4f, -0.1f),
                                   glm::vec3(0.0f, 0.0f, 1.0f), glm::vec3(3.0f, 2.0f, 0.5f)}) {
        std::vector<glm::vec3> directions;
        for (int k = 0; k < kRays; ++k) {  // a spherical Fibonacci set
            const float z = 1.0f - 2.0f * (k + 0.5f) / kRays, r = std::sqrt(1.0f - z * z), phi = 2.39996323f * k;
            directions.push_back(glm::normalize(glm::vec3(r * std::cos(phi), r * std::sin(phi), z)));
        }
        std::vector<std::optional<RayCaster::Hit>> packed(kRays);
        caster.intersect(origin, directions.data(), kRays, 1e-5f, packed.data());
        for (int k = 0; k < kRays; ++k, ++rays) {
            const auto single = caster.intersect(origin, directions[k], 1e-5f);
            ASSERT_EQ(bool(single), bool(packed[k])) << "ray " << k;
            if (!single) continue;
            ++hits;
            EXPECT_EQ(single->distance, packed[k]->distance) << "ray " << k;
            EXPECT_EQ(single->triangle, packed[k]->triangle) << "ray " << k;
            EXPECT_EQ(single->normal, packed[k]->normal) << "ray " << k;
        }
    }
    EXPECT_GT(hits, rays / 3);  // the walls and the sphere are met, ...
    EXPECT_LT(hits, rays);      // ... and the outside origin's rays away from them miss
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
