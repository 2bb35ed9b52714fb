// The small-scale structure's solid texture, sub-balls and glints against closed forms and independent Monte Carlo.
#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/optics/fresnel.h"
#include "firn/structure/cell_balls.h"
#include "firn/structure/glints.h"
#include "firn/structure/sub_balls.h"
#include "firn/util/error.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {
namespace {

TEST(CellBalls, SmallBallsMatchTheNoOverlapClosedForm) {
    // Balls of 0.1 cells almost never overlap: the Monte Carlo must reach 4/3 pi R^3 (1 + v^2) and
    // 64 pi / 315 R^3 (1 + v^2) within its noise (~1 % at 200,000 samples and 0.4 % coverage).
    const CellBalls balls{0.1, 0.5};
    const CellBallMeans mc = cellBallMeans(balls, 1000000, 7), exact = cellBallMeansWithoutOverlap(balls);
    EXPECT_NEAR(mc.coverage / exact.coverage, 1.0, 0.03);
    EXPECT_NEAR(mc.kernel / exact.kernel, 1.0, 0.03);
}

TEST(CellBalls, OverlapsLoseCoverage) {
    // Large balls overlap, and a point counts once: less coverage than the sum of the balls.
    const CellBalls balls{0.5, 0.0};
    const CellBallMeans mc = cellBallMeans(balls), sum = cellBallMeansWithoutOverlap(balls);
    EXPECT_LT(mc.coverage, 0.95 * sum.coverage);
    EXPECT_GT(mc.coverage, 0.5 * sum.coverage);
}

TEST(CellBalls, DeterministicForASeed) {
    const CellBalls balls{0.3, 0.2};
    EXPECT_EQ(cellBallMeans(balls, 1000, 3).kernel, cellBallMeans(balls, 1000, 3).kernel);
    EXPECT_NE(cellBallMeans(balls, 1000, 3).kernel, cellBallMeans(balls, 1000, 4).kernel);
    EXPECT_THROW(cellBallMeans({1.5, 0.0}), InvalidArgument);
    EXPECT_THROW(cellBallMeans({0.3, 1.0}), InvalidArgument);
}

TEST(SubBalls, DensityFactorKeepsTheMeanAtEveryDepth) {
    // Independent lattices sampled here (not by cellBallMeans): the factor's mean over space is 1 in the shallow
    // region, halfway through the fade and below it.
    SubBallSettings settings;
    settings.radius = 0.4e-3, settings.variation = 0.3, settings.depth = 3.0;
    const SubBallPattern pattern = subBallPattern(settings, 2000.0);
    EXPECT_NEAR(pattern.cellSize, 1.2e-3, 1e-12);
    EXPECT_NEAR(pattern.fadeEnd, 1.5e-3, 1e-12);
    for (const double depth : {0.0, 1.1e-3, 5e-3}) {
        double sum = 0.0;
        const int n = 400000;
        for (int s = 0; s < n; ++s) {
            Rng rng(99, s);
            const glm::dvec3 x{rng.uniform(), rng.uniform(), rng.uniform()};
            double nearest = 1e9, radius = 0.0;
            for (int i = -1; i <= 1; ++i)
                for (int j = -1; j <= 1; ++j)
                    for (int k = -1; k <= 1; ++k) {
                        const glm::dvec3 c{i + rng.uniform(), j + rng.uniform(), k + rng.uniform()};
                        const double r = pattern.balls.radius * (1.0 + pattern.balls.variation * (2.0 * rng.uniform() - 1.0));
                        const double d = glm::length(c - x);
                        if (d < nearest) nearest = d, radius = r;
                    }
            sum += pattern.densityFactor(nearest, radius, depth);
        }
        EXPECT_NEAR(sum / n, 1.0, 0.03) << "depth " << depth;
    }
    // Below the fade the density is untouched; at the centre of a grain it is many times the mean.
    EXPECT_EQ(pattern.densityFactor(0.0, pattern.balls.radius, 2e-3), 1.0);
    EXPECT_GT(pattern.densityFactor(0.0, pattern.balls.radius, 0.0), 20.0);
    EXPECT_EQ(pattern.densityFactor(0.9, pattern.balls.radius, 0.0), 0.0);
}

TEST(Glints, FacetDensityIsWhatAPlaneCuts) {
    GlintSettings settings;
    settings.facetsPerSquareMetre = 1e5, settings.facetRadius = 0.5e-3;
    const GlintFacets facets = glintFacets(settings);
    // 2 R / c^3 centres per m^2 lie within R of a plane.
    EXPECT_NEAR(2.0 * settings.facetRadius / std::pow(facets.cellSize, 3), settings.facetsPerSquareMetre, 1.0);
    EXPECT_GT(facets.coverage, 0.0);
    EXPECT_LT(facets.coverage, M_PI * settings.facetRadius * settings.facetRadius * settings.facetsPerSquareMetre);
    settings.facetsPerSquareMetre = 1.01 / (4.0 * settings.facetRadius * settings.facetRadius);
    EXPECT_THROW(glintFacets(settings), InvalidArgument);
}

TEST(Glints, MeanRadianceMatchesMonteCarloOfMirrorFacets) {
    // Independent Monte Carlo: facet normals uniform over the hemisphere facing the viewer; a facet adds
    // F(n.v) E / Omega when the mirror direction of v falls in the sun's cap. Viewer 70 deg from the normal, sun
    // opposite (half vector 70 deg from the view), cap radius 2 deg, irradiance 1.
    const double eta = 1.31, theta = 70.0 * kPi / 180.0, alpha = 2.0 * kPi / 180.0;
    const glm::dvec3 v{std::sin(theta), 0.0, std::cos(theta)}, sun{-std::sin(theta), 0.0, std::cos(theta)};
    const double omega = 2.0 * kPi * (1.0 - std::cos(alpha));
    double sum = 0.0, mirrored = 0.0;
    const int n = 4000000;
    for (int s = 0; s < n; ++s) {
        Rng rng(5, s);
        const double z = 2.0 * rng.uniform() - 1.0, phi = 2.0 * kPi * rng.uniform();
        glm::dvec3 normal{std::sqrt(1.0 - z * z) * std::cos(phi), std::sqrt(1.0 - z * z) * std::sin(phi), z};
        if (glm::dot(normal, v) < 0.0) normal = -normal;
        const glm::dvec3 r = reflect(-v, normal);
        if (glm::dot(r, sun) < std::cos(alpha)) continue;
        sum += fresnelReflectance(glm::dot(normal, v), eta) / omega;
        mirrored += 1.0;
    }
    const double cosHalf = std::cos(theta);  // the half vector is the surface normal here
    const double coverage = 0.2;
    EXPECT_NEAR(coverage * sum / n / meanGlintRadiance(coverage, eta, cosHalf), 1.0, 0.05);
    EXPECT_NEAR(coverage * mirrored / n / glintFraction(coverage, omega, cosHalf), 1.0, 0.05);
}

}  // namespace
}  // namespace firn
