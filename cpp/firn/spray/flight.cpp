#include "firn/spray/flight.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <glm/geometric.hpp>
#include <openvdb/tools/Interpolation.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/spray/snow_level_set.h"
#include "firn/util/ceil_count.h"
#include "firn/util/error.h"

namespace firn {

namespace {

constexpr int kMaxSnowSamples = 64;     // level-set samples along one step's chord, at most
constexpr int kBisections = 10;         // refinements of a crossing into the snow
constexpr double kObjectGap = 1e-4;     // m a particle stops short of a triangle it meets
constexpr double kUnsupported = 2.0;    // voxels above the snow at which a resting particle falls again

using SurfaceSampler = openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler>;

// Drag alone for time t: the direction holds, the speed falls as s0 / (1 + k s0 t).
void dragFlow(glm::dvec3 &x, glm::dvec3 &v, double t, double k) {
    const double s0 = glm::length(v);
    const double ks0t = k * s0 * t;
    // ln(1 + a) / (k s0) -> t as k s0 t -> 0; log1p keeps it exact there (k = 0 gives exactly t).
    const double drift = ks0t > 0.0 ? std::log1p(ks0t) / (k * s0) : t;  // s: distance / s0
    x += drift * v;
    v /= 1.0 + ks0t;
}

// The level set along the chord a -> b; the parameter (0..1) of the last point outside the snow before the first
// one inside, if the chord enters it. a is outside.
std::optional<double> snowEntry(const SurfaceSampler &phi, const glm::dvec3 &a, const glm::dvec3 &b, double h) {
    const auto at = [&](double t) {
        return snowLevelSetAt(phi, a + t * (b - a));
    };
    const int n = ceilCount(glm::length(b - a) / h, kMaxSnowSamples);
    double outside = 0.0;
    for (int i = 1; i <= n; ++i) {
        double inside = double(i) / n;
        if (at(inside) >= 0.0) {
            outside = inside;
            continue;
        }
        for (int r = 0; r < kBisections; ++r) {
            const double mid = 0.5 * (outside + inside);
            (at(mid) >= 0.0 ? outside : inside) = mid;
        }
        return outside;
    }
    return std::nullopt;
}

// The chance per step that a flying lump splits, drawn first from its stream for the step.
bool breaksNow(const SprayParticle &p, Rng &rng, double dt, const LumpSettings &lumps) {
    const double u = rng.uniform();
    return p.state == ParticleState::Flying && p.ballCount >= 2 && u < -std::expm1(-lumps.breakRate * dt);
}

// Moves one flying particle by a step, stopping it where it meets the snow or a triangle.
void fly(SprayParticle &p, double dt, const glm::dvec3 &g, double k, const SprayColliders &c,
         const std::optional<SurfaceSampler> &phi) {
    const glm::dvec3 start = p.position;
    glm::dvec3 end = start, velocity = p.velocity;
    flightStep(end, velocity, dt, g, k);
    double stopAt = 1.0;
    ParticleState landed = ParticleState::Flying;
    if (phi) {
        if (const auto t = snowEntry(*phi, start, end, c.snowSurface->voxelSize()[0]))
            stopAt = *t, landed = ParticleState::OnSnow;
    }
    const double length = glm::length(end - start);
    if (c.objects && length > 0.0) {
        const glm::dvec3 direction = (end - start) / length;
        if (const auto hit = c.objects->intersect(glm::vec3(start), glm::vec3(direction), 0.0f,
                                                  float(stopAt * length))) {
            stopAt = std::max(0.0, double(hit->distance) - kObjectGap) / length;
            landed = ParticleState::OnObject;
        }
    }
    if (landed == ParticleState::Flying) {
        p.position = end, p.velocity = velocity;
        return;
    }
    p.position = start + stopAt * (end - start);
    p.velocity = glm::dvec3(0.0);
    p.state = landed;
}

}  // namespace

void FlightSettings::validate() const {
    const auto check = [](bool ok, const char *what) {
        if (!ok) throw InvalidArgument(std::string("spray flight settings: ") + what);
    };
    check(std::abs(glm::length(down) - 1.0) < 1e-6, "the down axis must be a unit vector");
    check(gravity >= 0.0 && gravity < 1e3, "gravity must be between 0 and 1000 m/s^2");
    check(airDensity >= 0.0 && airDensity < 100.0, "air density must be between 0 and 100 kg/m^3");
    check(dragCoefficient >= 0.0 && dragCoefficient < 10.0, "drag coefficient must be between 0 and 10");
}

double dragPerSpeedSquared(double radius, double lumpDensity, const FlightSettings &s) {
    return 3.0 * s.airDensity * s.dragCoefficient / (8.0 * lumpDensity * radius);
}

double terminalSpeed(double radius, double lumpDensity, const FlightSettings &s) {
    return std::sqrt(s.gravity / dragPerSpeedSquared(radius, lumpDensity, s));
}

void flightStep(glm::dvec3 &x, glm::dvec3 &v, double dt, const glm::dvec3 &g, double k) {
    dragFlow(x, v, 0.5 * dt, k);
    v += g * dt;
    dragFlow(x, v, 0.5 * dt, k);
}

void advanceParticles(SprayParticles &particles, const FlightStep &step, const SprayColliders &c,
                      const FlightSettings &flight, const LumpSettings &lumps, bool deposit, std::uint64_t &nextId) {
    const glm::dvec3 g = flight.gravity * flight.down;
    const double h = c.snowSurface ? c.snowSurface->voxelSize()[0] : 0.0;
    std::vector<std::uint8_t> splits(particles.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, particles.size(), 256),
                      [&](const tbb::blocked_range<std::size_t> &r) {
        std::optional<openvdb::FloatGrid::ConstAccessor> accessor;
        std::optional<SurfaceSampler> phi;
        if (c.snowSurface) {
            accessor.emplace(c.snowSurface->getConstAccessor());
            phi.emplace(*accessor, c.snowSurface->transform());
        }
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            SprayParticle &p = particles[i];
            if (p.state == ParticleState::OnSnow && phi &&
                snowLevelSetAt(*phi, p.position) > kUnsupported * h)
                p.state = ParticleState::Flying;
            if (p.state != ParticleState::Flying) continue;
            fly(p, step.dt, g, dragPerSpeedSquared(p.radius, lumps.density, flight), c, phi);
            Rng rng = sprayRng(step.seed, SprayStream::Flight, p.id, step.index);
            splits[i] = breaksNow(p, rng, step.dt, lumps);
        }
    });
    SprayParticles halves;
    for (std::size_t i = 0; i < particles.size(); ++i) {
        if (!splits[i]) continue;
        Rng rng = sprayRng(step.seed, SprayStream::Flight, particles[i].id, step.index);
        breaksNow(particles[i], rng, step.dt, lumps);  // the same draw again: the split continues the stream
        halves.push_back(splitLump(particles[i], nextId++, lumps, rng));
    }
    particles.insert(particles.end(), halves.begin(), halves.end());
    if (!deposit)
        particles.erase(std::remove_if(particles.begin(), particles.end(),
                                       [](const SprayParticle &p) { return p.state != ParticleState::Flying; }),
                        particles.end());
}

}  // namespace firn
