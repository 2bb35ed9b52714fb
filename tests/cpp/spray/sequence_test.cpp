// Emission and whole frames: how many lumps an emitter throws and how, determinism whatever the thread count, and
// the state carried from frame to frame.
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/spray/sequence.h"
#include "firn/util/error.h"
#include "firn/util/threads.h"
#include "slab_snow.h"

namespace firn {
namespace {

EmitterRectangle ski(double x, double z) { return {{x, 0.0, z}, {0.4, 0.0, 0.0}, {0.0, 0.05, 0.0}}; }

TEST(Emission, AnEmitterInsideTheSnowThrowsRateTimesSweptVolume) {
    const SnowGrids snow = test::slabSnow({-1.0, -0.5, -0.5}, {1.0, 0.5, 0.0}, 0.02, 300.0f);
    EmissionSettings e;
    e.rate = 1e5;  // 1/m^3
    e.spreadAngle = 0.3;
    e.throwSpeed = 0.5;
    const double dt = 0.01, speed = 2.0;  // s, m/s
    std::uint64_t nextId = 10;
    const SprayParticles lumps = emitLumps(ski(0.0, -0.2), ski(speed * dt, -0.2), dt, *snow.surface, {0, 0, -1}, e,
                                           LumpSettings{}, 5, 0, 0, nextId, 1000000);
    const double expected = e.rate * speed * dt * 0.8 * 0.1;  // 160: rate x speed x time x area
    EXPECT_NEAR(double(lumps.size()), expected, 0.1 * expected);
    EXPECT_EQ(nextId, 10 + lumps.size());
    for (const SprayParticle &p : lumps) {
        const glm::dvec3 thrown = p.velocity - glm::dvec3(speed, 0.0, 0.0);
        EXPECT_NEAR(glm::length(thrown), 0.5 * speed, 1e-9);
        EXPECT_GE(thrown.z / glm::length(thrown), std::cos(0.3) - 1e-9);  // within the cone around up
        EXPECT_LE(std::abs(p.position.x), 0.4 + 1.5 * LumpSettings{}.radius);  // the balls' centre: within a lump
    }
    // Above the snow it throws nothing.
    EXPECT_TRUE(emitLumps(ski(0.0, 0.2), ski(speed * dt, 0.2), dt, *snow.surface, {0, 0, -1}, e, LumpSettings{}, 5,
                          0, 0, nextId, 1000000)
                    .empty());
    // Over the budget it refuses before allocating.
    EXPECT_THROW(emitLumps(ski(0.0, -0.2), ski(speed * dt, -0.2), dt, *snow.surface, {0, 0, -1}, e, LumpSettings{},
                           5, 0, 0, nextId, 10),
                 BudgetExceeded);
}

// An emitter skiing through the slab for `frames` frames, 2 cm under its top.
SprayScene skiing(std::size_t frames) {
    SprayScene scene;
    scene.fps = 24.0;
    Emitter e;
    for (std::size_t f = 0; f < frames; ++f) e.frames.push_back(ski(-0.6 + 6.0 * double(f) / scene.fps, -0.02));
    scene.emitters.push_back(e);
    return scene;
}

SprayState simulate(std::size_t frames, const SpraySettings &s) {
    SprayState state = initialSprayState(test::slabSnow({-1.5, -0.5, -0.3}, {1.5, 0.5, 0.0}, 0.02, 300.0f));
    const SprayScene scene = skiing(frames);
    while (state.frame + 1 < frames) simulateSprayFrame(state, scene, s, SubProgress(nullptr, 0, 1));
    return state;
}

void expectSameParticles(const SprayParticles &a, const SprayParticles &b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].id, b[i].id);
        EXPECT_EQ(a[i].position, b[i].position) << i;
        EXPECT_EQ(a[i].velocity, b[i].velocity) << i;
        EXPECT_EQ(a[i].state, b[i].state) << i;
        EXPECT_EQ(a[i].ballCount, b[i].ballCount) << i;
    }
}

// A ski whose sides are a whole number of cells long (80 cm, 10 cm: 40 and 5 cells of 2 cm) throws the same lumps
// when its sides carry a rounding (a snow layer moved in Blender maps the skis through float transforms): an extra
// cell would give every lump other random numbers.
TEST(Emission, ASideOfAWholeNumberOfCellsThrowsTheSameLumpsAfterARounding) {
    const SnowGrids snow = test::slabSnow({-1.0, -0.5, -0.5}, {1.0, 0.5, 0.0}, 0.02, 300.0f);
    EmissionSettings e;
    e.rate = 1e5;  // 1/m^3
    const double dt = 0.01, speed = 2.0;  // s, m/s
    const auto thrown = [&](double stretch) {
        EmitterRectangle from = ski(0.0, -0.2), to = ski(speed * dt, -0.2);
        for (EmitterRectangle *r : {&from, &to}) r->halfU *= stretch, r->halfV *= stretch;
        std::uint64_t nextId = 0;
        return emitLumps(from, to, dt, *snow.surface, {0, 0, -1}, e, LumpSettings{}, 5, 0, 0, nextId, 1000000);
    };
    const SprayParticles exact = thrown(1.0);
    ASSERT_GT(exact.size(), 100u);
    for (const double stretch : {1.0 - 1e-9, 1.0 + 1e-9}) {
        const SprayParticles rounded = thrown(stretch);
        ASSERT_EQ(rounded.size(), exact.size());
        for (std::size_t i = 0; i < exact.size(); ++i)
            EXPECT_LT(glm::length(rounded[i].position - exact[i].position), 1e-6);
    }
}

TEST(SpraySequence, SameSeedSameFramesWithOneOrTwoThreads) {
    SpraySettings s;
    s.seed = 4;
    s.lumps.breakRate = 3.0;
    setThreadCount(1);
    const SprayState one = runInCoreArena([&] { return simulate(6, s); });
    setThreadCount(2);
    const SprayState two = runInCoreArena([&] { return simulate(6, s); });
    setThreadCount(0);
    ASSERT_GT(one.particles.size(), 20u);
    EXPECT_EQ(one.nextId, two.nextId);
    expectSameParticles(one.particles, two.particles);
    EXPECT_EQ(one.snow.surface->activeVoxelCount(), two.snow.surface->activeVoxelCount());
    s.seed = 5;
    const SprayState other = simulate(6, s);
    EXPECT_TRUE(other.particles.size() != one.particles.size() ||
                other.particles.front().velocity != one.particles.front().velocity);
}

TEST(SpraySequence, LumpsFlyOutOfTheGrooveAndLandOnTheSnow) {
    SpraySettings s;
    const SprayState state = simulate(12, s);
    std::size_t above = 0;
    for (const SprayParticle &p : state.particles) {
        EXPECT_GE(test::levelSetAt(*state.snow.surface, p.position.x, p.position.y, p.position.z), 0.0) << p.id;
        above += p.position.z > 0.02;
    }
    EXPECT_GT(above, 10u);  // thrown up out of the snow
    const SnowGrids spray = spraySnapshot(state, s, SubProgress(nullptr, 0, 1));
    EXPECT_GT(spray.density->activeVoxelCount(), 0);
    float highest = 0.0f;
    for (auto it = spray.density->cbeginValueOn(); it; ++it) highest = std::max(highest, *it);
    EXPECT_LE(highest, float(s.lumps.density) * 1.0001f);
}

// An emitter that jumps 1e30 m within a sub-step would throw more lumps than a size_t holds: refused as over the
// budget, before its lumps' array is sized (the count wrapped around, the array was too short and the lumps were
// written past its end: tests/fuzz, spray).
TEST(Emission, AnEmitterJumpingFarIsRefusedOverTheBudget) {
    const SnowGrids snow = test::slabSnow({-1.0, -0.5, -0.5}, {1.0, 0.5, 0.0}, 0.02, 300.0f);
    std::uint64_t nextId = 0;
    EXPECT_THROW(emitLumps(ski(0.0, -0.2), ski(1e30, -0.2), 0.01, *snow.surface, {0, 0, -1}, EmissionSettings{},
                           LumpSettings{}, 5, 0, 0, nextId, 1000000),
                 BudgetExceeded);
    EXPECT_EQ(nextId, 0u);
}

// No limit on the lumps (an infinite budget) throws what the default budget does: the budget left converts to a
// count within range (a double of inf did not).
TEST(SpraySequence, AnInfiniteParticleBudgetThrowsAsAFiniteOne) {
    SpraySettings finite, infinite;
    infinite.maxParticles = std::numeric_limits<double>::infinity();
    const SprayState a = simulate(3, finite), b = simulate(3, infinite);
    ASSERT_GT(a.particles.size(), 0u);
    expectSameParticles(a.particles, b.particles);
}

TEST(SpraySequence, BadInputIsRefused) {
    SprayScene scene = skiing(3);
    scene.emitters.push_back(Emitter{{ski(0, 0)}});  // one frame where the other has three
    EXPECT_THROW(scene.validate(), InvalidArgument);
    scene = skiing(3);
    scene.emitters[0].frames[1].halfV = scene.emitters[0].frames[1].halfU;  // no area
    EXPECT_THROW(scene.validate(), InvalidArgument);
    scene = skiing(1);
    EXPECT_THROW(scene.validate(), InvalidArgument);
    SpraySettings s;
    s.substeps = 0;
    EXPECT_THROW(s.validate(), InvalidArgument);
    EXPECT_THROW(initialSprayState(SnowGrids{}), InvalidArgument);
}

}  // namespace
}  // namespace firn
