#include "firn/transport/sun_lobe.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <vector>

#include "firn/transport/half_space.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {
#include "firn/transport/sun_lobe_table.inc"

constexpr int kMuBins = 20, kPhiBins = 18;  // outgoing cos(zenith) in [0, 1], |azimuth| in [0, pi]
constexpr double kDeepTransportPaths = 30.0;

// omega of the similarity parameter y at this g (inverse of absorptionParameter).
double omegaOf(double y, double g) { return 1.0 - 3.0 * y * y * (1.0 - g) / 16.0; }

// Where x falls between table nodes: the lower node's index and the fraction towards the next.
template <std::size_t N>
void locate(const std::array<double, N> &nodes, double x, int &i, double &t) {
    x = std::clamp(x, nodes.front(), nodes.back());
    i = 0;
    while (i < int(N) - 2 && x > nodes[i + 1]) ++i;
    t = (x - nodes[i]) / (nodes[i + 1] - nodes[i]);
}
}  // namespace

double absorptionParameter(double omega, double g) {
    return 4.0 * std::sqrt(std::max(0.0, 1.0 - omega) / (3.0 * (1.0 - g)));
}

SunLobe fitSunLobe(double g, double mu0, double y, long photons, std::uint64_t seed) {
    Rng rng(seed, 0);
    const std::function<double()> uniform = [&rng] { return rng.uniform(); };
    const double omega = omegaOf(y, g);
    std::vector<double> counts(kMuBins * kPhiBins, 0.0);
    double deepReturn = 0.0;  // photons, in expectation
    const double maxDepth = kDeepTransportPaths / (1.0 - g);
    // Diffusion below maxDepth (optical depth units): kappa = sqrt(3 sigma_a sigma_tr), z_b = 2 D.
    const double kappa = std::sqrt(3.0 * (1.0 - omega) * (1.0 - omega * g));
    const double zb = 2.0 / (3.0 * (1.0 - omega * g));
    for (long i = 0; i < photons; ++i)
        walkPhoton(
            omega, g, std::numeric_limits<double>::infinity(), mu0, maxDepth, 0.0, 0.0, uniform,
            [&](double mu, double phi, bool) {
                const int m = std::min(kMuBins - 1, int(mu * kMuBins));
                const int p = std::min(kPhiBins - 1, int(std::abs(phi) / kPi * kPhiBins));
                counts[m * kPhiBins + p] += 1.0;
            },
            [&](double depth) {
                if (depth >= maxDepth) deepReturn += std::exp(-kappa * (depth + zb));
            });

    // Reflection function per bin: flux fraction / (projected solid angle / pi); deep photons add u(mu).
    struct Bin {
        double R, measure, f1, f2;  // R / A - 1 = b f1 + c f2 for the lobe
    };
    SunLobe lobe;
    lobe.albedo = deepReturn / photons;
    for (double n : counts) lobe.albedo += n / photons;
    if (lobe.albedo <= 0.0) return lobe;
    std::vector<Bin> bins;
    const double dPhi = kPi / kPhiBins;
    for (int m = 0; m < kMuBins; ++m) {
        const double muLo = double(m) / kMuBins, muHi = double(m + 1) / kMuBins, mu = 0.5 * (muLo + muHi);
        const double measure = 2.0 * dPhi * 0.5 * (muHi * muHi - muLo * muLo) / kPi;  // both signs of phi
        for (int p = 0; p < kPhiBins; ++p) {
            const double R = counts[m * kPhiBins + p] / photons / measure + deepReturn / photons * escapeFunction(mu);
            bins.push_back({R / lobe.albedo, measure, mu - 2.0 / 3.0,
                            std::sqrt(1.0 - mu * mu) * std::cos((p + 0.5) * dPhi)});
        }
    }
    // Least squares in relative error, reweighted by the current fit rather than by the noisy bins
    // (weighting by 1 / R_bin^2 would favour bins that happen to have few photons).
    for (int iteration = 0; iteration < 8; ++iteration) {
        double m11 = 0, m12 = 0, m22 = 0, v1 = 0, v2 = 0;
        for (const Bin &bin : bins) {
            const double fit = std::max(0.05, 1.0 + lobe.b * bin.f1 + lobe.c * bin.f2);
            const double w = iteration == 0 ? bin.measure : bin.measure / (fit * fit), r = bin.R - 1.0;
            m11 += w * bin.f1 * bin.f1, m12 += w * bin.f1 * bin.f2, m22 += w * bin.f2 * bin.f2;
            v1 += w * bin.f1 * r, v2 += w * bin.f2 * r;
        }
        const double det = m11 * m22 - m12 * m12;
        lobe.b = (v1 * m22 - v2 * m12) / det;
        lobe.c = (m11 * v2 - m12 * v1) / det;
    }
    lobe.a = 1.0 - 2.0 * lobe.b / 3.0;
    return lobe;
}

SunLobe sunLobe(double g, double mu0, double y) {
    int iy, ig, im;
    double ty, tg, tm;
    locate(kSunLobeY, y, iy, ty);
    locate(kSunLobeG, g, ig, tg);
    locate(kSunLobeMu0, mu0, im, tm);
    std::array<double, 3> v{};  // b, c, A
    for (int dy = 0; dy < 2; ++dy)
        for (int dg = 0; dg < 2; ++dg)
            for (int dm = 0; dm < 2; ++dm) {
                const double w = (dy ? ty : 1 - ty) * (dg ? tg : 1 - tg) * (dm ? tm : 1 - tm);
                for (int k = 0; k < 3; ++k) v[k] += w * kSunLobeTable[iy + dy][ig + dg][im + dm][k];
            }
    SunLobe lobe;
    lobe.b = v[0], lobe.c = v[1], lobe.albedo = v[2];
    lobe.a = 1.0 - 2.0 * lobe.b / 3.0;
    return lobe;
}


}  // namespace firn
