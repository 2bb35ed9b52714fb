// A ball of flat half-space patches, no light carried along or through the snow (docs/benchmarks.md, peak-refit):
// the share of the sun's returned power leaving beyond 90 and 120 deg from the sun when each patch, at angle psi
// from the point under the sun (mu0 = cos psi), returns the sun as the table's split (SunPeak with its fade), as the
// sun lobe alone, or as the half-space's Monte Carlo (walkPhoton, all orders). Its rows: each ring's shares; the
// last line: over the sunlit hemisphere, each ring weighted by the power it returns, to set beside
// bench/ball_energy_balance.py's ball (the difference is what the ball carries around and through itself).
//   g++ -O2 -std=c++17 -Icpp -Ibuild/cpp/generated bench/flat_patch_sphere.cpp build/cpp/libfirn_core.a -ltbb \
//       -o /tmp/flat_patch_sphere && /tmp/flat_patch_sphere [omega, 0.9999] [g, 0.85]
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <glm/vec3.hpp>
#include "firn/transport/half_space.h"
#include "firn/transport/source_lobe.h"
#include "firn/transport/sun_lobe.h"
#include "firn/util/random.h"
using namespace firn;
int main(int argc, char **argv) {
    const double pi = 3.141592653589793;
    const double omega = argc > 1 ? std::atof(argv[1]) : 0.9999, g = argc > 2 ? std::atof(argv[2]) : 0.85;
    const double y = absorptionParameter(omega, g);
    const double c90 = 0.0, c120 = std::cos(2 * pi / 3);
    // Photons deeper than this optical depth (300 transport paths at g 0.85) are dropped: at omega ~ 1 the walks'
    // length has no mean, and what returns from there is a few per mille and leaves as the escape function.
    constexpr double kMaxDepth = 2000.0;
    const int K = 40;  // patches in psi (angle from the sub-solar point), midpoint
    double W = 0, s90[3] = {0, 0, 0}, s120[3] = {0, 0, 0};
    for (int k = 0; k < K; ++k) {
        const double psi = (k + 0.5) / K * pi / 2, mu0 = std::cos(psi);
        // the direction to the sun in the patch frame (t = +x where the light travels): (-sin psi, 0, cos psi)
        auto cosTheta = [&](const glm::dvec3 &w) { return -std::sin(psi) * w.x + mu0 * w.z; };
        const SunLobe lobe = sunLobe(g, mu0, y);
        const double weight = std::sin(psi) * mu0 * lobe.albedo;  // the power the ring returns
        const SunPeak peak = sunPeak(g, mu0, y, lobe);
        const glm::dvec3 axis(std::cos(peak.elevation), 0.0, std::sin(peak.elevation));
        const int N = 150;
        double a90[2] = {0, 0}, a120[2] = {0, 0}, tot[2] = {0, 0};
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < 2 * N; ++j) {
                const double mu = (i + 0.5) / N, phi = -pi + (j + 0.5) / N * pi;
                const double s = std::sqrt(1 - mu * mu);
                const glm::dvec3 w(s * std::cos(phi), s * std::sin(phi), mu);
                const double f[2] = {lobeRadiance(peak.mean, 3.0 * peak.k * peak.mean * axis, w) +
                                         (1.0 - peak.share) * (peak.a() + peak.b * mu + peak.c * w.x),
                                     std::max(0.0, lobe.a + lobe.b * mu + lobe.c * w.x)};
                const double ct = cosTheta(w);
                for (int m = 0; m < 2; ++m) {
                    tot[m] += f[m] * mu;
                    if (ct < c90) a90[m] += f[m] * mu;
                    if (ct < c120) a120[m] += f[m] * mu;
                }
            }
        Rng rng(31 + k, 0);
        const std::function<double()> uniform = [&rng] { return rng.uniform(); };
        long returned = 0, b90 = 0, b120 = 0;
        for (long i = 0; i < 20000; ++i)
            walkPhoton(omega, g, std::numeric_limits<double>::infinity(), mu0, kMaxDepth, 0.0, 0.0, uniform,
                       [&](double mu, double phi, bool) {
                           ++returned;
                           const double s = std::sqrt(std::max(0.0, 1 - mu * mu));
                           const double ct = cosTheta(glm::dvec3(s * std::cos(phi), s * std::sin(phi), mu));
                           if (ct < c90) ++b90;
                           if (ct < c120) ++b120;
                       },
                       [](double) {});
        W += weight;
        for (int m = 0; m < 2; ++m) s90[m] += weight * a90[m] / tot[m], s120[m] += weight * a120[m] / tot[m];
        s90[2] += weight * double(b90) / returned, s120[2] += weight * double(b120) / returned;
        std::printf("psi %4.1f mu0 %.2f  beyond 90: split %.3f lobe %.3f MC %.3f   beyond 120: split %.3f lobe %.3f MC %.3f\n",
                    psi * 180 / pi, mu0, a90[0] / tot[0], a90[1] / tot[1], double(b90) / returned, a120[0] / tot[0],
                    a120[1] / tot[1], double(b120) / returned);
    }
    std::printf("sphere of flat patches, share beyond 90 / 120 deg: split %.3f / %.3f  lobe %.3f / %.3f  MC %.3f / %.3f\n",
                s90[0] / W, s120[0] / W, s90[1] / W, s120[1] / W, s90[2] / W, s120[2] / W);
}
