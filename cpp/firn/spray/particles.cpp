#include "firn/spray/particles.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

glm::dvec3 uniformDirection(Rng &rng) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    return sampleUniformCone(glm::dvec3(0.0, 0.0, 1.0), -1.0, u1, u2);
}

double cube(double x) { return x * x * x; }

// Radius (m) of the sphere whose volume is the balls' solid volume.
float equivalentRadius(const SprayParticle &p) {
    double volume = 0.0;  // / (4 pi / 3)
    for (int b = 0; b < p.ballCount; ++b) volume += cube(p.ballRadius[b] / kBallFieldToSolid);
    return float(std::cbrt(volume));
}

// Moves `position` to the balls' volume-weighted centre, keeping the balls where they are.
void recentre(SprayParticle &p) {
    glm::dvec3 centre(0.0);
    double volume = 0.0;
    for (int b = 0; b < p.ballCount; ++b) {
        const double v = cube(p.ballRadius[b]);
        centre += v * glm::dvec3(p.ballOffset[b]);
        volume += v;
    }
    centre /= volume;
    p.position += centre;
    for (int b = 0; b < p.ballCount; ++b) p.ballOffset[b] -= glm::vec3(centre);
}

}  // namespace

void LumpSettings::validate() const {
    const auto check = [](bool ok, const std::string &what) {
        if (!ok) throw InvalidArgument("spray lump settings: " + what);
    };
    check(radius > 1e-4 && radius < 1.0, "lump radius must be between 0.1 mm and 1 m");
    check(radiusVariation >= 0.0 && radiusVariation < 1.0, "lump radius variation must be in [0, 1)");
    check(density > 1.0 && density <= 917.0, "lump density must be between 1 and 917 kg/m^3 (ice)");
    check(ballsPerLump >= 1 && ballsPerLump <= kMaxBallsPerLump,
          "balls per lump must be between 1 and " + std::to_string(kMaxBallsPerLump));
    check(breakRate >= 0.0 && breakRate < 1e3, "break rate must be between 0 and 1000 per second");
    check(breakSpeed >= 0.0 && breakSpeed < 100.0, "break speed must be between 0 and 100 m/s");
}

SprayParticle makeLump(const glm::dvec3 &position, const glm::dvec3 &velocity, std::uint64_t id,
                       const LumpSettings &s, Rng &rng) {
    SprayParticle p;
    p.position = position;
    p.velocity = velocity;
    p.id = id;
    p.ballCount = std::uint8_t(s.ballsPerLump);
    const double radius = s.radius * (1.0 + s.radiusVariation * (2.0 * rng.uniform() - 1.0));
    const double solid = radius / std::cbrt(double(s.ballsPerLump));  // m, each ball's solid radius
    // Ball centres uniform in a sphere of the lump's radius less a ball's: the balls overlap into one lump.
    const double reach = radius - solid;
    for (int b = 0; b < s.ballsPerLump; ++b) {
        const double r = reach * std::cbrt(rng.uniform());
        p.ballOffset[b] = glm::vec3(r * uniformDirection(rng));
        p.ballRadius[b] = float(kBallFieldToSolid * solid);
    }
    recentre(p);
    p.radius = equivalentRadius(p);
    return p;
}

double lumpMass(const SprayParticle &p, double lumpDensity) {
    return lumpDensity * 4.0 / 3.0 * kPi * cube(p.radius);
}

SprayParticle splitLump(SprayParticle &p, std::uint64_t newId, const LumpSettings &s, Rng &rng) {
    if (p.ballCount < 2) throw InvalidArgument("a lump of one ball cannot split");
    const glm::dvec3 normal = uniformDirection(rng);
    // The balls in order along the normal (insertion sort: a handful of them).
    std::array<int, kMaxBallsPerLump> order{};
    std::array<double, kMaxBallsPerLump> along{};
    for (int b = 0; b < p.ballCount; ++b) {
        order[b] = b;
        along[b] = glm::dot(glm::dvec3(p.ballOffset[b]), normal);
        for (int j = b; j > 0 && along[order[j]] < along[order[j - 1]]; --j) std::swap(order[j], order[j - 1]);
    }
    const int kept = p.ballCount / 2;
    SprayParticle other = p;
    other.id = newId;
    const SprayParticle whole = p;
    p.ballCount = std::uint8_t(kept);
    other.ballCount = std::uint8_t(whole.ballCount - kept);
    for (int i = 0; i < whole.ballCount; ++i) {
        SprayParticle &half = i < kept ? p : other;
        const int slot = i < kept ? i : i - kept;
        half.ballOffset[slot] = whole.ballOffset[order[i]];
        half.ballRadius[slot] = whole.ballRadius[order[i]];
    }
    // The halves keep their parent's reference point (moving it to their own centres could carry it across a
    // surface the parent was outside of).
    p.radius = equivalentRadius(p);
    other.radius = equivalentRadius(other);
    // Equal and opposite momenta along the normal: m_a dv_a = -m_b dv_b, dv_b - dv_a = breakSpeed.
    const double ma = cube(p.radius), mb = cube(other.radius);
    p.velocity -= s.breakSpeed * mb / (ma + mb) * normal;
    other.velocity += s.breakSpeed * ma / (ma + mb) * normal;
    return other;
}

}  // namespace firn
