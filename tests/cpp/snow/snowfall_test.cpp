#include "firn/snow/snowfall.h"

#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/geometry/ray_caster.h"
#include "firn/util/error.h"
#include "test_geometry.h"

namespace firn {

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;
const SubProgress kNoProgress(nullptr, 0.0, 1.0);
}  // namespace

TEST(RayCaster, HitsAndMisses) {
    const RayCaster caster(test::box({-1, -1, 1}, {1, 1, 2}));
    EXPECT_TRUE(caster.occluded({0, 0, 0}, {0, 0, 1}));
    EXPECT_FALSE(caster.occluded({0, 0, 0}, {0, 0, -1}));
    EXPECT_FALSE(caster.occluded({0, 0, 0}, {0, 0, 1}, 0.0f, 0.5f));  // segment ends before the box
    const auto hit = caster.intersect({0, 0, 0}, {0, 0, 1});
    ASSERT_TRUE(hit);
    EXPECT_FLOAT_EQ(hit->distance, 1.0f);
    EXPECT_NEAR(hit->normal.z, -1.0f, 1e-6f);  // the box's bottom faces down
    EXPECT_FALSE(RayCaster(TriangleMesh{}).occluded({0, 0, 0}, {0, 0, 1}));
}

TEST(Snowfall, SlopeCoverFollowsProjectedSnowfallAndEndsAtTheMaximum) {
    const double maxSlope = 60.0 * kDeg;
    EXPECT_DOUBLE_EQ(slopeCover(0.0, maxSlope), 1.0);
    EXPECT_DOUBLE_EQ(slopeCover(30.0 * kDeg, maxSlope), std::cos(30.0 * kDeg));  // below the sliding band
    EXPECT_EQ(slopeCover(60.0 * kDeg, maxSlope), 0.0);
    EXPECT_EQ(slopeCover(75.0 * kDeg, maxSlope), 0.0);
    double previous = 1.0;
    for (double a = 0.0; a <= 60.0; a += 1.0) {  // monotone and continuous up to the maximum
        const double c = slopeCover(a * kDeg, maxSlope);
        EXPECT_LE(c, previous);
        EXPECT_LT(previous - c, 0.12);
        previous = c;
    }
}

TEST(Snowfall, SitesHaveTheRequestedDensityOnOpenGround) {
    SnowfallSettings s;
    s.spacing = 0.05;
    const TriangleMesh ground = test::plane(2.0f);
    const auto sites = findLandingSites(ground, RayCaster(ground), s, kNoProgress);
    EXPECT_NEAR(double(sites.size()), 4.0 / (0.05 * 0.05), 2.0);  // two triangles, each rounds once
    for (const LandingSite &site : sites) {
        EXPECT_FLOAT_EQ(site.cover, 1.0f);
        EXPECT_NEAR(site.normal.z, 1.0f, 1e-6f);
        EXPECT_LE(std::abs(site.position.x), 1.0f);
    }
}

TEST(Snowfall, DepthWeightsScaleTheCoverLinearlyOverEachTriangle) {
    SnowfallSettings s;
    s.spacing = 0.05;
    const TriangleMesh ground = test::plane(2.0f);  // corners (-1,-1), (1,-1), (1,1), (-1,1)
    // Weight 0 on the left edge, 1 on the right: linear in x over both triangles, so the cover is (x + 1) / 2.
    const auto sites = findLandingSites(ground, RayCaster(ground), s, kNoProgress, {0.0f, 1.0f, 1.0f, 0.0f});
    ASSERT_GT(sites.size(), 1000u);
    for (const LandingSite &site : sites) EXPECT_NEAR(site.cover, 0.5f * (site.position.x + 1.0f), 1e-5f);
    EXPECT_THROW(findLandingSites(ground, RayCaster(ground), s, kNoProgress, {1.0f}), InvalidArgument);
}

TEST(Snowfall, ShelterIsTheBlockedFractionOfTheSnowfallCone) {
    SnowfallSettings s;
    s.spacing = 0.02;
    s.spread = 20.0 * kDeg;
    s.exposureRays = 64;
    const TriangleMesh ground = test::plane(3.0f);
    const TriangleMesh roof = test::box({-0.5f, -0.5f, 1.0f}, {0.5f, 0.5f, 1.1f});
    const auto sites = findLandingSites(ground, RayCaster(merge({ground, roof})), s, kNoProgress);
    const double edge = 0.5 + 1.1 * std::tan(s.spread);  // beyond this, no ray of the cone meets the roof
    int partial = 0;
    for (const LandingSite &site : sites) {
        const double d = std::max(std::abs(site.position.x), std::abs(site.position.y));
        EXPECT_GT(d, 0.5 - 1.0 * std::tan(s.spread) - 0.01) << "snow under the roof";
        if (d > edge + 0.01) {
            EXPECT_FLOAT_EQ(site.cover, 1.0f);
        }
        if (site.cover < 1.0f) ++partial;
    }
    EXPECT_GT(partial, 50);  // a soft edge, not a hard line
}

TEST(Snowfall, SameSeedSameSites) {
    SnowfallSettings s;
    s.seed = 3;
    const TriangleMesh ground = test::plane(1.0f);
    const RayCaster caster(ground);
    const auto a = findLandingSites(ground, caster, s, kNoProgress);
    const auto b = findLandingSites(ground, caster, s, kNoProgress);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].position, b[i].position);
    s.seed = 4;
    EXPECT_NE(findLandingSites(ground, caster, s, kNoProgress)[0].position, a[0].position);
}

}  // namespace firn
