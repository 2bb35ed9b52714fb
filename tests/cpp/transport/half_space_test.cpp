#include "firn/transport/half_space.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "firn/transport/sun_lobe.h"

namespace firn {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Exact semi-infinite values: adding-doubling and Chandrasekhar H-functions (notes: snow-optics.md).
TEST(HalfSpace, MonteCarloMatchesExactPlaneAlbedo) {
    struct Case { double g, omega, mu0, exact; };
    for (const Case &c : {Case{0.0, 0.999, 1.0, 0.91285}, Case{0.0, 0.99, 0.5, 0.81514}, Case{0.87, 0.999, 1.0, 0.77340}}) {
        const SlabResponse r = slabMonteCarlo(c.omega, c.g, kInf, c.mu0, 40000, 7);
        EXPECT_NEAR(r.reflectance, c.exact, 4.0 * r.reflectanceError) << "g " << c.g << " omega " << c.omega;
    }
}

TEST(HalfSpace, MonteCarloMatchesExactSphericalAlbedo) {
    const SlabResponse r = slabMonteCarlo(0.99, 0.0, kInf, -1.0, 40000, 3);  // uniform sky
    EXPECT_NEAR(r.reflectance, 0.79456, 4.0 * r.reflectanceError);
}

TEST(HalfSpace, ConservativeSlabLosesNothing) {
    const SlabResponse r = slabMonteCarlo(1.0, 0.85, 8.0, 0.6, 20000, 5);
    EXPECT_DOUBLE_EQ(r.reflectance + r.transmittance, 1.0);  // analog transport: every photon leaves
    EXPECT_GT(r.transmittance, 0.3);
}

// ART (Kokhanovsky & Zege 2004) is within 0.5 % of the exact values for omega >= 0.999 (notes).
TEST(HalfSpace, AsymptoticFormulasMatchExactTable) {
    EXPECT_NEAR(artSphericalAlbedo(0.999, 0.0), 0.92971, 0.005 * 0.92971);
    EXPECT_NEAR(artPlaneAlbedo(0.9999, 0.87, 1.0), 0.92182, 0.005 * 0.92182);
    EXPECT_NEAR(artPlaneAlbedo(0.9999, 0.87, 0.5), 0.94594, 0.005 * 0.94594);
}

// The sun lobe's shape keeps the flux it is given, a non-absorbing half-space returns all light, and the lobe
// leans forwards for slanting sun.
TEST(SunLobe, ConservesFluxAndLeansForward) {
    for (double y : {0.0, 0.5, 2.0})
        for (double g : {0.0, 0.5, 0.85})
            for (double mu0 : {0.2, 0.5, 1.0}) {
                const SunLobe lobe = sunLobe(g, mu0, y);
                EXPECT_NEAR(lobe.a + 2.0 * lobe.b / 3.0, 1.0, 1e-12);
                EXPECT_GT(lobe.a - std::abs(lobe.c), 0.0) << "negative radiance at grazing, g " << g << " mu0 " << mu0;
                if (y == 0.0) {
                    EXPECT_DOUBLE_EQ(lobe.albedo, 1.0);
                }
            }
    EXPECT_GT(sunLobe(0.85, 0.3).c, 0.3);
    EXPECT_NEAR(sunLobe(0.85, 1.0).c, 0.0, 0.05);  // overhead sun: no preferred azimuth
    // Absorption takes most from long paths, which spread the light: what returns leans further forward.
    EXPECT_GT(sunLobe(0.85, 0.3, 2.0).c, sunLobe(0.85, 0.3, 0.0).c + 0.1);
}

// The absorbing table's albedos against exact half-space values (adding-doubling and H-functions, the same
// as HalfSpace.MonteCarloMatchesExact*; notes: snow-optics.md), through y and the trilinear interpolation.
TEST(SunLobe, AbsorbingTableMatchesExactAlbedos) {
    EXPECT_NEAR(sunLobe(0.0, 0.5, absorptionParameter(0.99, 0.0)).albedo, 0.81514, 0.015 * 0.81514);
    EXPECT_NEAR(sunLobe(0.87, 1.0, absorptionParameter(0.999, 0.87)).albedo, 0.77340, 0.015 * 0.77340);
    EXPECT_NEAR(sunLobe(0.87, 1.0, absorptionParameter(0.9999, 0.87)).albedo, 0.92182, 0.01 * 0.92182);
    EXPECT_NEAR(sunLobe(0.0, 1.0, absorptionParameter(0.999, 0.0)).albedo, 0.91285, 0.01 * 0.91285);
}

// The table is what its generator computes (to its Monte Carlo noise).
TEST(SunLobe, TableMatchesItsGenerator) {
    for (double y : {0.0, 0.75}) {
        const SunLobe table = sunLobe(0.8, 0.7, y), fresh = fitSunLobe(0.8, 0.7, y, 20000, 11);
        EXPECT_NEAR(table.b, fresh.b, 0.06) << "y " << y;
        EXPECT_NEAR(table.c, fresh.c, 0.06) << "y " << y;
        EXPECT_NEAR(table.albedo, fresh.albedo, 0.02) << "y " << y;
    }
}

}  // namespace firn
