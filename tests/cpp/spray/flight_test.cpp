// Lumps in flight: the exact ballistic step, the terminal speed under quadratic drag, landing on snow and objects,
// splitting.
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/spray/flight.h"
#include "firn/spray/snow_level_set.h"
#include "firn/spray/tracks.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"
#include "slab_snow.h"
#include "test_geometry.h"

namespace firn {
namespace {

const glm::dvec3 kDown(0.0, 0.0, -1.0);

// Flies one particle for `seconds` in `steps` steps of flightStep.
glm::dvec3 flyFor(glm::dvec3 x, glm::dvec3 &v, double seconds, int steps, double k, double g = 9.81) {
    for (int i = 0; i < steps; ++i) flightStep(x, v, seconds / steps, g * kDown, k);
    return x;
}

TEST(Flight, WithoutDragTheBallisticPathIsExactAtAnySubStepCount) {
    // x(t) = x0 + v0 t + g t^2 / 2 (constant acceleration).
    const glm::dvec3 x0(0.3, -1.0, 2.0), v0(4.0, 1.5, 6.0);
    const glm::dvec3 exact = x0 + v0 * 1.0 + 0.5 * 9.81 * kDown;
    for (int steps : {1, 3, 17}) {
        glm::dvec3 v = v0;
        const glm::dvec3 x = flyFor(x0, v, 1.0, steps, 0.0);
        EXPECT_LT(glm::length(x - exact), 1e-3) << steps << " sub-steps";  // m; in fact ~1e-15
        EXPECT_LT(glm::length(v - (v0 + 9.81 * kDown)), 1e-9) << steps;
    }
}

TEST(Flight, WithDragALumpFallsToTheTerminalSpeedOfItsSize) {
    FlightSettings air;
    const double density = 250.0;  // kg/m^3
    for (double radius : {0.005, 0.02}) {
        const double k = dragPerSpeedSquared(radius, density, air);
        // v_t = sqrt(2 m g / (rho_air C_d A)), m = rho 4/3 pi r^3, A = pi r^2.
        const double mass = density * 4.0 / 3.0 * kPi * std::pow(radius, 3), area = kPi * radius * radius;
        const double vt = std::sqrt(2.0 * mass * 9.81 / (air.airDensity * air.dragCoefficient * area));
        EXPECT_NEAR(terminalSpeed(radius, density, air), vt, 1e-9 * vt);
        // Falling from rest: v(t) = v_t tanh(g t / v_t) (Taylor, Classical Mechanics (2005) eq. 2.57).
        glm::dvec3 v(0.0);
        flyFor(glm::dvec3(0.0), v, 1.0, 96, k);
        EXPECT_NEAR(-v.z, vt * std::tanh(9.81 / vt), 1e-3 * vt) << radius;
        v = glm::dvec3(0.0);
        flyFor(glm::dvec3(0.0), v, 15.0 * vt / 9.81, 2000, k);
        EXPECT_NEAR(-v.z, vt, 1e-4 * vt) << radius;
        // Thrown down at twice the terminal speed, it slows to it.
        v = glm::dvec3(0.0, 0.0, -2.0 * vt);
        flyFor(glm::dvec3(0.0), v, 15.0 * vt / 9.81, 2000, k);
        EXPECT_NEAR(-v.z, vt, 1e-4 * vt) << radius;
        // Stable at any frame rate: half-second steps still settle near it, never overshoot to nonsense.
        v = glm::dvec3(0.0, 0.0, -2.0 * vt);
        flyFor(glm::dvec3(0.0), v, 20.0, 40, k);
        EXPECT_NEAR(-v.z, vt, 0.05 * vt) << radius;
    }
}

TEST(Flight, NoLumpEndsInsideAnObjectOrBelowTheSnow) {
    const SnowGrids snow = test::slabSnow({-1.0, -1.0, -0.3}, {1.0, 1.0, 0.0}, 0.02, 300.0f);
    const glm::vec3 lo(0.1f, -0.3f, -0.05f), hi(0.5f, 0.3f, 0.4f);  // a block standing in the snow
    const RayCaster block(test::box(lo, hi));
    LumpSettings lumps;
    lumps.breakRate = 2.0;
    SprayParticles particles;
    Rng rng(7, 0);
    for (std::uint64_t i = 0; i < 3000; ++i) {
        const glm::dvec3 x(rng.uniform() * 1.6 - 0.8, rng.uniform() * 1.6 - 0.8, 0.05 + rng.uniform());
        const glm::dvec3 v(rng.uniform() * 8.0 - 4.0, rng.uniform() * 8.0 - 4.0, rng.uniform() * 8.0 - 2.0);
        if (x.x > lo.x - 0.05 && x.x < hi.x + 0.05 && x.y > lo.y - 0.05 && x.y < hi.y + 0.05 && x.z < hi.z + 0.05)
            continue;  // starts clear of the block
        particles.push_back(makeLump(x, v, i, lumps, rng));
    }
    std::uint64_t nextId = 3000;
    for (std::uint64_t step = 0; step < 96; ++step)
        advanceParticles(particles, {1.0 / 48.0, 1, step}, {snow.surface.get(), &block}, FlightSettings{}, lumps,
                         true, nextId);
    std::size_t onSnow = 0, onObject = 0;
    for (const SprayParticle &p : particles) {
        const glm::dvec3 x = p.position;
        const bool inBlock = x.x > lo.x && x.x < hi.x && x.y > lo.y && x.y < hi.y && x.z > lo.z && x.z < hi.z;
        EXPECT_FALSE(inBlock) << p.id;
        EXPECT_GE(test::levelSetAt(*snow.surface, x.x, x.y, x.z), 0.0) << p.id;
        onSnow += p.state == ParticleState::OnSnow, onObject += p.state == ParticleState::OnObject;
    }
    EXPECT_GT(onSnow, 1000u);
    EXPECT_GT(onObject, 10u);
    EXPECT_GT(particles.size(), 3000u * 0.9);  // splits added lumps
}

TEST(Flight, WithoutDepositLandedLumpsVanishAndCutAwaySnowLetsOthersFallAgain) {
    SnowGrids snow = test::slabSnow({-0.5, -0.5, -0.3}, {0.5, 0.5, 0.0}, 0.02, 300.0f);
    LumpSettings lumps;
    Rng rng(2, 2);
    SprayParticles dropped{makeLump({0.0, 0.0, 0.3}, {0.0, 0.0, 0.0}, 0, lumps, rng)};
    std::uint64_t nextId = 1;
    for (std::uint64_t step = 0; step < 48 && !dropped.empty(); ++step)
        advanceParticles(dropped, {1.0 / 48.0, 1, step}, {snow.surface.get(), nullptr}, FlightSettings{}, lumps, false,
                         nextId);
    EXPECT_TRUE(dropped.empty());  // it landed within 1 s (a 0.3 m fall takes 0.25 s) and was taken into the snow

    SprayParticles resting{makeLump({0.0, 0.0, 0.3}, {0.0, 0.0, 0.0}, 0, lumps, rng)};
    for (std::uint64_t step = 0; step < 48; ++step)
        advanceParticles(resting, {1.0 / 48.0, 1, step}, {snow.surface.get(), nullptr}, FlightSettings{}, lumps, true,
                         nextId);
    ASSERT_EQ(resting.front().state, ParticleState::OnSnow);
    EXPECT_NEAR(resting.front().position.z, 0.0, 0.02);
    // A groove 10 cm deep cut under it: it falls to the groove's floor.
    const std::vector<EmitterRectangle> under{{{0.0, 0.0, -0.05}, {0.1, 0.0, 0.0}, {0.0, 0.1, 0.0}}};
    TrackSettings track;
    track.thickness = 0.05;
    ASSERT_GT(carveTrack(snow, under, kDown, track, 50e6).carvedVoxels, 0u);
    for (std::uint64_t step = 48; step < 96; ++step)
        advanceParticles(resting, {1.0 / 48.0, 1, step}, {snow.surface.get(), nullptr}, FlightSettings{}, lumps, true,
                         nextId);
    EXPECT_EQ(resting.front().state, ParticleState::OnSnow);
    EXPECT_NEAR(resting.front().position.z, -0.1, 0.02);
}

TEST(Flight, ASplitConservesMomentumAndBalls) {
    LumpSettings lumps;
    lumps.ballsPerLump = 5;
    lumps.breakSpeed = 0.4;
    Rng rng(3, 1);
    SprayParticle a = makeLump({1.0, 2.0, 3.0}, {2.0, 0.0, 1.0}, 0, lumps, rng);
    const double massBefore = lumpMass(a, lumps.density);
    const glm::dvec3 momentum = massBefore * a.velocity;
    const SprayParticle b = splitLump(a, 1, lumps, rng);
    const double ma = lumpMass(a, lumps.density), mb = lumpMass(b, lumps.density);
    EXPECT_EQ(a.ballCount + b.ballCount, 5);
    EXPECT_NEAR(ma + mb, massBefore, 1e-6 * massBefore);  // volumes add: radius^3 is the balls' sum
    EXPECT_LT(glm::length(ma * a.velocity + mb * b.velocity - momentum), 1e-9);
    EXPECT_NEAR(glm::length(b.velocity - a.velocity), 0.4, 1e-9);
    LumpSettings single;
    single.ballsPerLump = 1;
    SprayParticle c = makeLump({0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 2, single, rng);
    EXPECT_THROW(splitLump(c, 3, single, rng), InvalidArgument);
}

// Past 2^30 voxels from the grid's origin OpenVDB's sampler floors a point into an int it overflows (undefined: an
// emitter moved 1e30 m, tests/fuzz spray seed 42 under UBSan): the spray reads such points, and non-finite ones,
// as outside the snow, and the snow itself as before.
TEST(SnowLevelSet, PastTheIndexRangeAPointIsOutsideTheSnow) {
    const SnowGrids snow = test::slabSnow({-0.5, -0.3, -0.3}, {0.5, 0.3, 0.0}, 0.01, 300.0f);
    const SnowSampler phi(*snow.surface);
    EXPECT_NEAR(snowLevelSetAt(phi, {0.0, 0.0, -0.02}), -0.02, 1e-3);  // m, inside
    EXPECT_NEAR(snowLevelSetAt(phi, {0.0, 0.0, 0.01}), 0.01, 1e-3);    // in the band above
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(snowLevelSetAt(phi, {1e31, 0.0, 0.0}), inf);
    EXPECT_EQ(snowLevelSetAt(phi, {0.0, -1e31, -0.02}), inf);
    EXPECT_EQ(snowLevelSetAt(phi, {0.0, 0.0, std::numeric_limits<double>::quiet_NaN()}), inf);
}

TEST(Flight, BadSettingsAreRefused) {
    FlightSettings f;
    f.down = {0.0, 0.0, -2.0};
    EXPECT_THROW(f.validate(), InvalidArgument);
    LumpSettings l;
    l.ballsPerLump = 9;
    EXPECT_THROW(l.validate(), InvalidArgument);
    l = LumpSettings{};
    l.density = 2000.0;
    EXPECT_THROW(l.validate(), InvalidArgument);
}

}  // namespace
}  // namespace firn
