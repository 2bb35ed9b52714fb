// Where the sun's light leaves a ball of uniform snow against where it entered (docs/benchmarks.md, clean-flow):
// photons walked forwards (delta tracking; the core's Rng and Henyey-Greenstein sampling) from a parallel beam along
// -z onto a ball of radius R, its surface sharp (h 0) or the suite's balls' (bench/bake_suite.py `ball`: voxels of
// fill clip(0.5 - (r - R) / h) read trilinearly, taken radially: that ramp convolved with a tent of one voxel, from
// R - 1.5 h to R + 1.5 h). Entry and exit: the first and the last scattering. Printed, per W entering:
//   - light leaving the lit side (exit psi < 90 deg from the point under the sun) by its great-circle distance from
//     the entry in transport mean free paths 1/sigma_tr; past the terminator, around the limb (never deeper than
//     kLimbDepth transport paths below r = R; of it, never below r = R: the ramp's skin) or through the body;
//   - the exit directions' share beyond 90 / 120 deg from the sun (bench/ball_energy_balance.py's, the
//     truth 0.317 / 0.151 on ball_clean), all and by the beam's impact parameter b / R;
//   - the power leaving per 5 deg ring of psi, to set beside the bake's surface light per ring.
//   g++ -O2 -std=c++17 -Icpp bench/ball_exit_distance.cpp -o /tmp/ball_exit_distance
//   /tmp/ball_exit_distance [R m, 0.04] [sigma_t 1/m, 6000] [omega, 1-1e-7] [g, 0.85] [photons, 100000] [h m, 0]
//       [deepest: transport paths below R past which photons are dropped and counted (a nearly flat ball), none]
// ball_clean: 0.04 6000 0.9999999 0.85 400000 0.005; ball_snow: 0.08 2000 0.9999 0.85 200000 0.01.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "firn/util/random.h"
#include "firn/util/sampling.h"

using namespace firn;

namespace {

constexpr double kLimbDepth = 9.0;  // transport paths: two of ball_clean's 5 mm voxels

// The suite's ball's fill across its surface at u = (r - R) / h: the voxels' ramp clip(0.5 - u) convolved with the
// trilinear tent 1 - |v| (midpoint rule).
double rampFill(double u) {
    constexpr int kSteps = 2000;
    double sum = 0.0;
    for (int m = 0; m < kSteps; ++m) {
        const double v = -1.0 + 2.0 * (m + 0.5) / kSteps;
        sum += (1.0 - std::abs(v)) * std::clamp(0.5 - (u - v), 0.0, 1.0) * 2.0 / kSteps;
    }
    return sum;
}

// Power leaving and its part beyond 90 and 120 deg from the sun (+z).
struct Forward {
    double all = 0.0, beyond90 = 0.0, beyond120 = 0.0;
    void add(double w, const glm::dvec3 &d) {
        all += w;
        if (d.z < 0.0) beyond90 += w;
        if (d.z < -0.5) beyond120 += w;
    }
    void print(const char *label) const {
        if (all > 0.0) std::printf("  %s  %.4f / %.4f\n", label, beyond90 / all, beyond120 / all);
    }
};

}  // namespace

int main(int argc, char **argv) {
    const double R = argc > 1 ? std::atof(argv[1]) : 0.04, sigmaT = argc > 2 ? std::atof(argv[2]) : 6000.0;  // m, 1/m
    const double omega = argc > 3 ? std::atof(argv[3]) : 1.0 - 1e-7, g = argc > 4 ? std::atof(argv[4]) : 0.85;
    const long photons = argc > 5 ? std::atol(argv[5]) : 100000;
    const double h = argc > 6 ? std::atof(argv[6]) : 0.0;  // m
    const double tmfp = 1.0 / (sigmaT * (1.0 - g));          // m
    const double deepest = (argc > 7 ? std::atof(argv[7]) : 1e9) * tmfp;  // m below R
    const double bound = R + 1.5 * h;                                      // m: the snow's outer edge
    std::vector<double> profile(4001);                                     // rampFill over u in [-2, 2]
    for (std::size_t k = 0; k < profile.size(); ++k) profile[k] = rampFill(-2.0 + 4.0 * k / (profile.size() - 1));
    const auto fill = [&](const glm::dvec3 &x) {
        if (h <= 0.0) return glm::dot(x, x) <= R * R ? 1.0 : 0.0;
        const double u = std::clamp((glm::length(x) - R) / h, -2.0, 2.0);
        return profile[std::size_t(std::lround((u + 2.0) / 4.0 * (profile.size() - 1)))];
    };
    const double edges[] = {0.5, 1.0, 2.25, 4.5, 9.0, 18.0, 36.0, 1e300};  // transport paths
    const double impactEdges[] = {0.8, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1e300};
    constexpr int kRings = 36;
    double lit[8] = {}, limb = 0.0, skin = 0.0, body = 0.0, entered = 0.0, dropped = 0.0;
    Forward all, byImpact[8];
    std::vector<double> ring(kRings, 0.0);
    Rng rng(0, 0);
    for (long n = 0; n < photons; ++n) {
        const double b = bound * std::sqrt(rng.uniform()), a = 2.0 * kPi * rng.uniform();  // m, rad
        glm::dvec3 x(b * std::cos(a), b * std::sin(a), std::sqrt(bound * bound - b * b)), d(0.0, 0.0, -1.0);
        glm::dvec3 in(0.0), out(0.0);
        double weight = 1.0, below = -1e300;  // the deepest scattering below r = R, m
        bool scattered = false;
        for (;;) {
            const double s = -std::log(1.0 - rng.uniform()) / sigmaT;  // to the next event against sigma_t
            const double p = glm::dot(x, d), q = glm::dot(x, x) - bound * bound;
            if (s >= -p + std::sqrt(std::max(0.0, p * p - q))) break;  // leaves the ball first
            x += s * d;
            if (rng.uniform() >= fill(x)) continue;  // a null collision
            if (!scattered) in = x, scattered = true, entered += 1.0;
            out = x;
            below = std::max(below, R - glm::length(x));
            if (below > deepest) break;
            weight *= omega;
            d = sampleHenyeyGreenstein(d, g, rng.uniform(), rng.uniform());
        }
        if (!scattered) continue;
        if (below > deepest) {
            dropped += weight;
            continue;
        }
        int impact = 0;
        while (b / R > impactEdges[impact]) ++impact;
        all.add(weight, d), byImpact[impact].add(weight, d);
        const double psi = std::acos(std::clamp(out.z / glm::length(out), -1.0, 1.0));
        ring[std::min(kRings - 1, int(psi / kPi * kRings))] += weight;
        if (out.z >= 0.0) {
            const double arc =
                glm::length(out) * std::acos(std::clamp(glm::dot(glm::normalize(in), glm::normalize(out)), -1.0, 1.0));
            int k = 0;
            while (arc / tmfp > edges[k]) ++k;
            lit[k] += weight;
        } else if (below <= kLimbDepth * tmfp) {
            limb += weight;
            if (below <= 0.0) skin += weight;
        } else {
            body += weight;
        }
    }
    std::printf("ball R %.3f m, sigma_t %.0f /m, omega %.8f, g %.2f, ramp h %.4f m: 1/sigma_tr %.3f mm, R %.1f "
                "transport paths; %.0f of %ld photons met the snow (cross-section %.2f cm^2), dropped %.4f\n",
                R, sigmaT, omega, g, h, tmfp * 1e3, R / tmfp, entered, photons,
                entered / double(photons) * kPi * bound * bound * 1e4, dropped / entered);
    std::printf("leaving the lit side by great-circle distance from the entry (transport paths), per W entering:\n");
    double cumulative = 0.0;
    for (int k = 0; k < 8; ++k) {
        cumulative += lit[k] / entered;
        std::printf("  <= %5.2f  %.4f  (cumulative %.4f)\n", std::min(edges[k], 999.0), lit[k] / entered, cumulative);
    }
    std::printf("past the terminator: around the limb %.4f (of it never below r = R %.4f), through the body %.4f\n",
                limb / entered, skin / entered, body / entered);
    std::printf("exit directions beyond 90 / 120 deg from the sun, all and by impact parameter b / R (its share):\n");
    all.print("all        ");
    char label[32];
    for (int k = 0; k < 8; ++k) {
        std::snprintf(label, sizeof label, "b/R <= %4.2f (%.3f)", std::min(impactEdges[k], 9.99),
                      byImpact[k].all / all.all);
        byImpact[k].print(label);
    }
    std::printf("power leaving per 5 deg ring of psi, per W entering:\n ");
    for (double p : ring) std::printf(" %.4f", p / entered);
    std::printf("\n");
}
