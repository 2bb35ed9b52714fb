// The brute-force grain renderer: exact cases, energy conservation, and the pile albedo against KZ04.
#include <cmath>
#include <utility>

#include <gtest/gtest.h>

#include "firn/optics/fresnel.h"
#include "firn/grains/grain_pile.h"
#include "firn/grains/grain_tracer.h"
#include "firn/grains/sphere_optics.h"
#include "firn/optics/kz04.h"
#include "firn/util/error.h"
#include "firn/util/threads.h"
#include "test_geometry.h"

namespace firn {
namespace {

constexpr double kEta = 1.31;

TEST(GrainTracer, ARayThroughTheCentreOfOneSphere) {
    // Along the axis every ray stays on the axis: reflected (R) or through after p chords, all to the sky of
    // radiance 1. L = R + (1 - R)^2 T / (1 - R T), T = exp(-gamma 2 r), R = ((n - 1)/(n + 1))^2.
    GrainSet grains;
    grains.add({0, 0, 0}, 1e-3);
    GrainMaterials m;
    m.iceAbsorption = Rgb(0.0, 200.0, 1000.0);  // 1/m: T = 1, 0.67, 0.135
    const TriangleMesh nothing;
    const GrainTracer tracer(nothing, grains, m);
    const auto estimate = tracer.radiance({GrainRay{{0, 0, 1}, {0, 0, -1}}}, 20000, 3);
    const double R = std::pow((kEta - 1.0) / (kEta + 1.0), 2);
    for (int c = 0; c < 3; ++c) {
        const double T = std::exp(-m.iceAbsorption[c] * 2e-3);
        const double expected = R + (1 - R) * (1 - R) * T / (1 - R * T);
        EXPECT_NEAR(estimate[0].mean[c], expected, 4.0 * estimate[0].standardError[c] + 1e-12) << c;
    }
}

TEST(GrainTracer, ADiffuseGroundUnderAUniformSky) {
    // A Lambertian plane of albedo a under a sky of radiance 1 has radiance a (it sees only sky).
    GrainMaterials m;
    m.surfaces = {GrainSurface{Rgb(0.2, 0.5, 0.9), false}};
    const TriangleMesh ground = test::plane(10.0f);
    const GrainSet noGrains;
    const GrainTracer tracer(ground, noGrains, m);
    const auto e = tracer.radiance({GrainRay{{0.1, 0.2, 1.0}, glm::normalize(glm::dvec3(0.2, 0, -1))}}, 2000, 1);
    EXPECT_NEAR(e[0].mean.x, 0.2, 4.0 * e[0].standardError.x + 1e-12);
    EXPECT_NEAR(e[0].mean.z, 0.9, 4.0 * e[0].standardError.z + 1e-12);
}

TEST(GrainTracer, SameSeedSameRadianceWhateverTheThreadsAndCancel) {
    GrainSet grains;
    for (int i = 0; i < 50; ++i) grains.add({0.003 * (i % 7), 0.003 * (i / 7), 0.001}, 1e-3);
    const TriangleMesh ground = test::plane(0.1f);
    GrainMaterials m;
    m.iceAbsorption = Rgb(20.0, 5.0, 1.0);
    const GrainTracer tracer(ground, grains, m);
    std::vector<GrainRay> rays;
    for (int i = 0; i < 64; ++i) rays.push_back({{0.0003 * i, 0.01, 0.05}, glm::normalize(glm::dvec3(0.1, 0.2, -1))});
    setThreadCount(1);
    const auto one = runInCoreArena([&] { return tracer.radiance(rays, 16, 7); });
    setThreadCount(0);
    const auto all = runInCoreArena([&] { return tracer.radiance(rays, 16, 7); });
    for (std::size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(one[i].mean, all[i].mean) << i;
    const auto other = tracer.radiance(rays, 16, 8);
    bool differs = false;
    for (std::size_t i = 0; i < rays.size(); ++i) differs = differs || other[i].mean != all[i].mean;
    EXPECT_TRUE(differs);
    Progress progress;
    progress.cancel();
    EXPECT_THROW(tracer.radiance(rays, 16, 7, &progress), Cancelled);
}

GrainPile pile(double radius, double widthInRadii, double depthInRadii, std::uint64_t seed) {
    PileSettings s;
    s.radius = radius;
    s.width = widthInRadii * radius;
    s.depth = depthInRadii * radius;
    s.seed = seed;
    return buildGrainPile(s);
}

TEST(GrainPile, ConservesEnergyWithoutAbsorption) {
    // Clear ice over a white ground in a mirror box: every path must come back out of the top.
    const GrainPile p = pile(1e-3, 12, 30, 5);
    const PileAlbedo a = measurePileAlbedo(p, kEta, Rgb(0.0), Rgb(1.0), 2000, 9);
    EXPECT_EQ(a.stats.bailedOut, 0u);
    EXPECT_GT(a.stats.meanEvents, 20.0);  // the paths did wander through the grains
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a.mean[c], 1.0, 1e-9);
    // A grey ground (albedo 0.5) under the same grains absorbs some light: the estimate must show it.
    const PileAlbedo grey = measurePileAlbedo(p, kEta, Rgb(0.0), Rgb(0.5), 2000, 9);
    EXPECT_LT(grey.mean.x, 1.0 - 5.0 * grey.standardError.x);
}

TEST(GrainPile, PackingIsDenseAndMeasured) {
    const GrainPile p = pile(1e-3, 20, 40, 2);
    const double f = pileVolumeFraction(p, 2e-3, 0.2 * p.top, 0.7 * p.top);
    // Below random close packing of equal spheres (0.64, Scott & Kilgour 1969): Chrisman's deposition keeps
    // each grain where it first touched (no rolling), which packs loosely, like fresh snow. Sanity bounds only.
    EXPECT_GT(f, 0.15);
    EXPECT_LT(f, 0.64);
}

// The validation of the volumetric optics: the plane albedo (mu0 = 1) of a deep pile of grains, rendered grain
// by grain, against Kokhanovsky & Zege's asymptotic formula r_p = exp(-(9/7) 4 sqrt((1 - omega) / (3 (1 - g))))
// for the spheres' own omega and g (sphere_optics.h; KZ04 eq. for the plane albedo, snow-optics notes). Ice
// absorbs too little in the visible for a pile of test size to be semi-infinite, so the test uses Warren &
// Brandt's ice at 800 nm (gamma = 2.1 1/m), where grains of 0.5-2 mm absorb 0.2-0.7 % per pass (1 - omega) and
// the pile is 6 diffusion lengths deep. Measured (bench/grains_bench.py, docs/grains.md): the grains are 2 %
// brighter than ART at 0.5 mm, 3-6 % at 2 mm depending on the pile (ART itself is 1 % low there against exact
// transport with the same omega and g). So the goal of 5 % on A is tested at 0.5 mm and 7 % at 2 mm, and
// 1 - A, the sensitive quantity, to 15 %.
double semiInfiniteDepth(double radius, double gamma, double volumeFraction) {
    // Diffusion length L_d = l_tr / sqrt(3 (1 - omega) / (1 - g)), l_tr = 1 / (sigma_t (1 - g)) (m).
    const SphereRayOptics s = sphereRayOptics(kEta, gamma, radius);
    const double sigmaT = packedSphereOptics(s, volumeFraction, radius, false).sigmaT;
    const double transportLength = 1.0 / (sigmaT * (1.0 - s.g));
    return 6.0 * transportLength / std::sqrt(3.0 * s.absorptionEfficiency / (1.0 - s.g));
}

TEST(GrainPile, AlbedoMatchesKz04) {
    const double gamma = 2.1048670779051606;  // 1/m: 4 pi kappa / lambda, kappa(800 nm) = 1.34e-7 (Warren & Brandt 2008)
    // Piles of ~10^4 grains differ from one another by ~2 % in albedo (more than the path noise), so each size
    // averages three piles of its own seeds.
    constexpr int kPiles = 3;
    double previous = 0.0;
    for (const auto &[r, tolerance] : {std::pair{2e-3, 0.07}, std::pair{0.5e-3, 0.05}}) {
        double albedo = 0.0, variance = 0.0, whiteSky = 0.0;
        for (int k = 0; k < kPiles; ++k) {
            PileSettings s;
            s.radius = r;
            s.width = 20.0 * r;
            s.depth = semiInfiniteDepth(r, gamma, 0.24);
            s.seed = 11 + k;
            const GrainPile p = buildGrainPile(s);
            const PileAlbedo a = measurePileAlbedo(p, kEta, Rgb(gamma), Rgb(0.0), 10000, 4 + k);
            EXPECT_EQ(a.stats.bailedOut, 0u);
            albedo += a.mean.x / kPiles;
            variance += a.standardError.x * a.standardError.x / (kPiles * kPiles);
            whiteSky += measurePileAlbedo(p, kEta, Rgb(gamma), Rgb(0.0), 5000, 40 + k, nullptr, PileLight::Diffuse).mean.x / kPiles;
        }
        // Under a uniform sky (KZ04's spherical albedo r_s = exp(-y)) the grains agree to ~1 % (docs/grains.md).
        const double kz04WhiteSky = kz04SpherePileAlbedo(kEta, Rgb(gamma), r, true).x;
        EXPECT_NEAR(whiteSky / kz04WhiteSky, 1.0, 0.05) << "r = " << r << ": grains " << whiteSky << ", KZ04 " << kz04WhiteSky;
        const double kz04 = kz04SpherePileAlbedo(kEta, Rgb(gamma), r).x;
        EXPECT_NEAR(albedo / kz04, 1.0, tolerance) << "r = " << r << " m: grains " << albedo << ", KZ04 " << kz04;
        EXPECT_NEAR((1.0 - albedo) / (1.0 - kz04), 1.0, 0.15) << "r = " << r;
        // Bigger grains absorb more per pass: the pile of 2 mm grains is darker, far beyond the noise.
        if (previous > 0.0) {
            EXPECT_GT(albedo, previous + 10.0 * std::sqrt(variance));
        }
        previous = albedo;
    }
}

}  // namespace
}  // namespace firn
