#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/util/random.h"

namespace firn {

// Snow thrown by moving objects (Nishita et al. 1997): each particle is a lump of snow drawn as a small cluster
// of metaballs (Wyvill's degree-6 field, geometry/metaball.h), so that a lump is not a sphere.

constexpr int kMaxBallsPerLump = 8;

// Where a particle is in its life.
enum class ParticleState : std::uint8_t {
    Flying = 0,    // moves under gravity and drag, collides with the snow and the objects
    OnSnow = 1,    // came to rest on the snow surface
    OnObject = 2,  // came to rest on an object's triangles
};

// One lump. Its balls are offsets from `position`, its reference point (the balls' centre when it is thrown; the
// halves of a split keep their parent's), which is what flies and collides; a ball's field radius R is twice its solid radius, as the
// Wyvill field of a lone ball crosses the snow's iso-value 1/2 at exactly u = r / R = 1/2
// (1 - 22/9 u^2 + 17/9 u^4 - 4/9 u^6 = 1/2 at u = 1/2).
struct SprayParticle {
    glm::dvec3 position{0.0};  // m, world
    glm::dvec3 velocity{0.0};  // m/s
    std::uint64_t id = 0;      // unique in a simulation; names the particle's random stream
    float radius = 0.0f;       // m, of the sphere of the same volume as the balls (solid radii): mass and drag
    ParticleState state = ParticleState::Flying;
    std::uint8_t ballCount = 0;
    std::array<glm::vec3, kMaxBallsPerLump> ballOffset{};  // m from `position`
    std::array<float, kMaxBallsPerLump> ballRadius{};      // m, field radius (zero at it)
};

using SprayParticles = std::vector<SprayParticle>;

// Field radius / solid radius of one ball (see SprayParticle).
constexpr double kBallFieldToSolid = 2.0;

struct LumpSettings {
    double radius = 0.01;         // m, mean equivalent-sphere radius of a new lump
    double radiusVariation = 0.5;  // 0..1: radius x (1 + variation (2u - 1)), u uniform
    double density = 250.0;       // kg/m^3 of a lump (packed snow thrown by a ski: 150-400)
    int ballsPerLump = 4;         // 1..kMaxBallsPerLump
    double breakRate = 0.5;       // 1/s: chance per second a flying lump of two balls or more splits in two
    double breakSpeed = 0.3;      // m/s: relative speed of the two halves after a split

    // Throws InvalidArgument naming the first setting out of range.
    void validate() const;
};

// A new lump of random size at `position`: its balls at random offsets within the lump, their solid radii
// r / n^(1/3), so that the balls' volume is the lump's.
SprayParticle makeLump(const glm::dvec3 &position, const glm::dvec3 &velocity, std::uint64_t id,
                       const LumpSettings &settings, Rng &rng);

// kg: lump density x the volume of the equivalent sphere.
double lumpMass(const SprayParticle &particle, double lumpDensity);

// Splits a lump of two balls or more in two, across a random plane through its reference point: `particle` keeps
// one half, the returned lump (id `newId`) takes the other, both at the same reference point. Momentum is conserved; the halves separate at
// settings.breakSpeed along the plane's normal.
SprayParticle splitLump(SprayParticle &particle, std::uint64_t newId, const LumpSettings &settings, Rng &rng);

// The random stream of one purpose and two counters (a particle id, a sub-step...), independent of threads.
enum class SprayStream : std::uint64_t { Emission = 1, Flight = 2 };
inline Rng sprayRng(std::uint64_t seed, SprayStream purpose, std::uint64_t a, std::uint64_t b) {
    return Rng(seed, mix64(std::uint64_t(purpose) ^ mix64(a ^ mix64(b))));
}

}  // namespace firn
