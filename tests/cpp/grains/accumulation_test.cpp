// Chrisman's accumulation: where grains land, what is discarded, determinism, bad input.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "firn/grains/accumulation.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"
#include "firn/util/threads.h"
#include "test_geometry.h"

namespace firn {
namespace {

AccumulationSettings settings(std::size_t count, double radius, std::uint64_t seed = 1) {
    AccumulationSettings s;
    s.count = count;
    s.radius = radius;
    s.radiusVariation = 0.3;
    s.seed = seed;
    return s;
}

// The deepest any two grains press into each other, as a fraction of the smaller radius (brute force, n^2).
double worstGrainOverlap(const GrainSet &g) {
    double worst = -1.0;
    for (std::size_t i = 0; i < g.size(); ++i)
        for (std::size_t j = i + 1; j < g.size(); ++j) {
            const double depth = g.radii[i] + g.radii[j] - glm::length(g.centres[i] - g.centres[j]);
            worst = std::max(worst, depth / std::min(g.radii[i], g.radii[j]));
        }
    return worst;
}

// Distance (m) from p to the axis-aligned box [lo, hi]; negative inside (depth below the nearest face).
double signedDistanceToBox(const glm::dvec3 &p, const glm::dvec3 &lo, const glm::dvec3 &hi) {
    const glm::dvec3 centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    const glm::dvec3 q = glm::abs(p - centre) - half;
    const double outside = glm::length(glm::max(q, glm::dvec3(0.0)));
    return outside + std::min(std::max({q.x, q.y, q.z}), 0.0);
}

TEST(Accumulation, GrainsRestOnAFlatPlaneWithoutOverlap) {
    const TriangleMesh ground = test::plane(0.1f);
    const AccumulationResult result = accumulateGrains(ground, settings(3000, 2e-3));
    const GrainSet &g = result.grains;
    ASSERT_EQ(g.size(), 3000u);
    for (std::size_t i = 0; i < g.size(); ++i) {
        EXPECT_GE(g.centres[i].z, g.radii[i] * (1.0 - kGrainOverlapTolerance) - 1e-9) << i;  // not in the ground
        EXPECT_GE(g.radii[i], 2e-3 * 0.7 - 1e-12);
        EXPECT_LE(g.radii[i], 2e-3 * 1.3 + 1e-12);
    }
    EXPECT_LE(worstGrainOverlap(g), kGrainOverlapTolerance + 1e-9);
    EXPECT_GT(result.overlapping, 0u);  // the rule did have grains to discard
    // Stacking happened: 3000 grains of ~2 mm over 100 mm x 100 mm need several layers.
    const double highest = std::max_element(g.centres.begin(), g.centres.end(),
                                            [](auto &a, auto &b) { return a.z < b.z; })->z;
    EXPECT_GT(highest, 6e-3);
}

TEST(Accumulation, SteepSurfacesGetNoGrains) {
    // 70 deg is steeper than the 60 deg limit: every hit is discarded. 50 deg is not.
    const TriangleMesh steep = test::plane(0.1f, {0, 0, 0}, float(70.0 * kPi / 180.0));
    AccumulationSettings s = settings(100, 1e-3);
    s.maxRays = 2000;
    const AccumulationResult none = accumulateGrains(steep, s);
    EXPECT_EQ(none.grains.size(), 0u);
    EXPECT_EQ(none.rays, 2000u);
    EXPECT_GT(none.steep, 1000u);  // the plane covers most of its own bounding box seen from above
    EXPECT_EQ(none.steep + none.missed, none.rays);

    const TriangleMesh gentle = test::plane(0.1f, {0, 0, 0}, float(50.0 * kPi / 180.0));
    EXPECT_EQ(accumulateGrains(gentle, s).grains.size(), 100u);
}

TEST(Accumulation, NoGrainInsideAnObject) {
    // A box standing on the ground: grains on its top and around it, none inside or pressed into it.
    TriangleMesh scene = merge({test::plane(0.2f), test::box({-0.03f, -0.03f, 0.0f}, {0.03f, 0.03f, 0.05f})});
    const AccumulationResult result = accumulateGrains(scene, settings(4000, 3e-3, 7));
    const GrainSet &g = result.grains;
    ASSERT_EQ(g.size(), 4000u);
    std::size_t onTop = 0;
    for (std::size_t i = 0; i < g.size(); ++i) {
        const double d = signedDistanceToBox(g.centres[i], {-0.03, -0.03, 0.0}, {0.03, 0.03, 0.05});
        EXPECT_GE(d, g.radii[i] * (1.0 - kGrainOverlapTolerance) - 1e-7) << i;
        if (g.centres[i].z > 0.05) ++onTop;
    }
    EXPECT_GT(onTop, 50u);
    EXPECT_LE(worstGrainOverlap(g), kGrainOverlapTolerance + 1e-9);
    EXPECT_GT(result.steep, 0u);  // the flanks of grains (and the box's rim) are steeper than 60 deg
}

TEST(Accumulation, SameSeedSameGrainsWhateverTheThreads) {
    const TriangleMesh ground = test::plane(0.05f);
    const AccumulationSettings s = settings(5000, 1e-3, 42);
    setThreadCount(1);
    const GrainSet one = runInCoreArena([&] { return accumulateGrains(ground, s).grains; });
    setThreadCount(0);
    const GrainSet all = runInCoreArena([&] { return accumulateGrains(ground, s).grains; });
    ASSERT_EQ(one.size(), all.size());
    EXPECT_EQ(one.centres, all.centres);
    EXPECT_EQ(one.radii, all.radii);

    const GrainSet other = accumulateGrains(ground, settings(5000, 1e-3, 43)).grains;
    EXPECT_NE(other.centres, all.centres);
}

TEST(Accumulation, AlongASlantedSnowfall) {
    // Snow falling at 30 deg from vertical still lands on a flat ground, on its upper side.
    AccumulationSettings s = settings(500, 1e-3);
    s.direction = {std::sin(0.5), 0.0, -std::cos(0.5)};
    const GrainSet g = accumulateGrains(test::plane(0.05f), s).grains;
    ASSERT_EQ(g.size(), 500u);
    for (std::size_t i = 0; i < g.size(); ++i) EXPECT_GT(g.centres[i].z, 0.0);
}

TEST(Accumulation, CancelAndBadInput) {
    const TriangleMesh ground = test::plane(0.05f);
    Progress progress;
    progress.cancel();
    EXPECT_THROW(accumulateGrains(ground, settings(100, 1e-3), &progress), Cancelled);
    EXPECT_THROW(accumulateGrains(ground, settings(kMaxGrainCount + 1, 1e-3)), BudgetExceeded);
    EXPECT_THROW(accumulateGrains(ground, settings(100, -1e-3)), InvalidArgument);
    EXPECT_THROW(accumulateGrains(ground, settings(0, 1e-3)), InvalidArgument);
    EXPECT_THROW(accumulateGrains(TriangleMesh{}, settings(10, 1e-3)), InvalidArgument);
    AccumulationSettings s = settings(10, 1e-3);
    s.radiusVariation = 1.0;
    EXPECT_THROW(accumulateGrains(ground, s), InvalidArgument);
    s = settings(10, 1e-3);
    s.direction = glm::dvec3(0.0);
    EXPECT_THROW(accumulateGrains(ground, s), InvalidArgument);
}

}  // namespace
}  // namespace firn
