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
}  // namespace

SunLobe fitSunLobe(double g, double mu0, long photons, std::uint64_t seed) {
    Rng rng(seed, 0);
    const std::function<double()> uniform = [&rng] { return rng.uniform(); };
    std::vector<double> counts(kMuBins * kPhiBins, 0.0);
    long deep = 0;
    const double maxDepth = kDeepTransportPaths / (1.0 - g);
    for (long i = 0; i < photons; ++i)
        walkPhoton(
            1.0, g, std::numeric_limits<double>::infinity(), mu0, maxDepth, 0.0, 0.0, uniform,
            [&](double mu, double phi, bool) {
                const int m = std::min(kMuBins - 1, int(mu * kMuBins));
                const int p = std::min(kPhiBins - 1, int(std::abs(phi) / kPi * kPhiBins));
                counts[m * kPhiBins + p] += 1.0;
            },
            [&](double) { ++deep; });

    // Reflection function per bin: flux fraction / (projected solid angle / pi); deep photons add u(mu).
    struct Bin {
        double R, measure, f1, f2;  // R - 1 = b f1 + c f2 for the lobe
    };
    std::vector<Bin> bins;
    const double dPhi = kPi / kPhiBins;
    for (int m = 0; m < kMuBins; ++m) {
        const double muLo = double(m) / kMuBins, muHi = double(m + 1) / kMuBins, mu = 0.5 * (muLo + muHi);
        const double measure = 2.0 * dPhi * 0.5 * (muHi * muHi - muLo * muLo) / kPi;  // both signs of phi
        for (int p = 0; p < kPhiBins; ++p) {
            const double R = counts[m * kPhiBins + p] / photons / measure + double(deep) / photons * escapeFunction(mu);
            bins.push_back({R, measure, mu - 2.0 / 3.0, std::sqrt(1.0 - mu * mu) * std::cos((p + 0.5) * dPhi)});
        }
    }
    // Least squares in relative error, reweighted by the current fit rather than by the noisy bins
    // (weighting by 1 / R_bin^2 would favour bins that happen to have few photons).
    SunLobe lobe;
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

SunLobe sunLobe(double g, double mu0) {
    const int ng = int(kSunLobeG.size()), nm = int(kSunLobeMu0.size());
    auto locate = [](const auto &nodes, double x, int &i, double &t) {
        const int n = int(nodes.size());
        x = std::clamp(x, nodes.front(), nodes.back());
        i = 0;
        while (i < n - 2 && x > nodes[i + 1]) ++i;
        t = (x - nodes[i]) / (nodes[i + 1] - nodes[i]);
    };
    int ig, im;
    double tg, tm;
    locate(kSunLobeG, g, ig, tg);
    locate(kSunLobeMu0, mu0, im, tm);
    (void)ng, (void)nm;
    auto at = [](int i, int j) { return kSunLobeBC[i][j]; };
    SunLobe lobe;
    for (int k = 0; k < 2; ++k) {
        const double v = (1 - tg) * ((1 - tm) * at(ig, im)[k] + tm * at(ig, im + 1)[k]) +
                         tg * ((1 - tm) * at(ig + 1, im)[k] + tm * at(ig + 1, im + 1)[k]);
        (k == 0 ? lobe.b : lobe.c) = v;
    }
    lobe.a = 1.0 - 2.0 * lobe.b / 3.0;
    return lobe;
}

}  // namespace firn
