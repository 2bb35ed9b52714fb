#include "firn/transport/sun_lobe.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>
#include <tbb/parallel_for.h>

#include "firn/transport/half_space.h"
#include "firn/transport/source_lobe.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {
#include "firn/transport/sun_lobe_table.inc"
#include "firn/transport/sun_peak_table.inc"

// Outgoing cos(zenith) in [0, 1], |azimuth| in [0, pi].
constexpr int kMuBins = kLimbMuBins, kPhiBins = kLimbAzimuthBins;
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

namespace {
// The reflection function of a half-space (sun_lobe.h's Monte Carlo) over outgoing bins, over its plane albedo.
struct Reflection {
    struct Bin {
        double R, measure;  // R / A; projected solid angle / pi (both signs of the azimuth)
        double mu, forward;  // bin centre: cos(zenith) and t . w
    };
    double albedo = 0.0;
    std::vector<Bin> bins;
};

Reflection halfSpaceReflection(double g, double mu0, double y, long photons, std::uint64_t seed) {
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
    Reflection out;
    out.albedo = deepReturn / photons;
    for (double n : counts) out.albedo += n / photons;
    if (out.albedo <= 0.0) return out;
    const double dPhi = kPi / kPhiBins;
    for (int m = 0; m < kMuBins; ++m) {
        const double muLo = double(m) / kMuBins, muHi = double(m + 1) / kMuBins, mu = 0.5 * (muLo + muHi);
        const double measure = 2.0 * dPhi * 0.5 * (muHi * muHi - muLo * muLo) / kPi;  // both signs of phi
        for (int p = 0; p < kPhiBins; ++p) {
            const double R = counts[m * kPhiBins + p] / photons / measure + deepReturn / photons * escapeFunction(mu);
            out.bins.push_back({R / out.albedo, measure, mu, std::sqrt(1.0 - mu * mu) * std::cos((p + 0.5) * dPhi)});
        }
    }
    return out;
}

// The linear form's basis functions beside the constant: mu - 2/3 and t . w (no flux of their own).
std::array<double, 2> linearBasis(const Reflection::Bin &bin) { return {bin.mu - 2.0 / 3.0, bin.forward}; }

// Least squares in relative error of R / A - 1 - sum_j x_j f_j(bin) over the bins, weighted by projected solid
// angle and reweighted by the current fit rather than by the noisy bins (weighting by 1 / R_bin^2 would favour
// bins that happen to have few photons). Returns the relative error's weighted sum of squares.
template <int N, typename Basis>
double fitRelative(const Reflection &r, const Basis &basis, std::array<double, N> &x) {
    x.fill(0.0);
    double error = 0.0;
    for (int iteration = 0; iteration < 8; ++iteration) {
        std::array<std::array<double, N + 1>, N> m{};  // normal equations, right-hand side last
        error = 0.0;
        for (std::size_t b = 0; b < r.bins.size(); ++b) {
            const Reflection::Bin &bin = r.bins[b];
            const std::array<double, N> f = basis(b);
            double fit = 1.0;
            for (int j = 0; j < N; ++j) fit += x[j] * f[j];
            fit = std::max(0.05, fit);
            const double w = iteration == 0 ? bin.measure : bin.measure / (fit * fit), res = bin.R - 1.0;
            error += bin.measure * (bin.R - fit) * (bin.R - fit) / (fit * fit);
            for (int j = 0; j < N; ++j) {
                for (int l = 0; l < N; ++l) m[j][l] += w * f[j] * f[l];
                m[j][N] += w * f[j] * res;
            }
        }
        for (int j = 0; j < N; ++j)  // Gauss-Jordan (the normal matrix is symmetric positive definite)
            for (int l = 0; l < N; ++l) {
                if (l == j) continue;
                const double factor = m[l][j] / m[j][j];
                for (int q = 0; q <= N; ++q) m[l][q] -= factor * m[j][q];
            }
        for (int j = 0; j < N; ++j) x[j] = m[j][N] / m[j][j];
    }
    return error;
}

// The linear form alone (b, c) and its error.
std::pair<std::array<double, 2>, double> fitLinear(const Reflection &r) {
    std::array<double, 2> x{};
    const double error = fitRelative<2>(r, [&](std::size_t b) { return linearBasis(r.bins[b]); }, x);
    return {x, error};
}

// The peaks the fit chooses from: k and elevation on a grid (kGrazingPeakElevationDegrees, at grazing sun only, then
// from kMinPeakElevationDegrees up).
constexpr int kPeakKs = 14, kPeakElevations = 14;
double peakK(int i) { return 0.3 + 0.05 * i; }
double peakElevation(int j) {
    return (j == 0 ? kGrazingPeakElevationDegrees : kMinPeakElevationDegrees + 5.0 * (j - 1)) * kPi / 180.0;
}

// A peak's shape over the bins, scaled to exitance 1 (over pi): bin b's mean radiance (over projected solid
// angle) of lobeRadiance(mean, 3 k m, w), m at `elevation` above the horizon towards the sun's travel. Bin means
// (8 x 8 points a bin), as the Monte Carlo's counts are, so that a sharp lobe near the horizon keeps its flux.
struct PeakShape {
    double k = 0.0, elevation = 0.0, mean = 0.0;
    std::vector<double> bins;
};

// A lobe's radiance (source_lobe.h) averaged over bin (m, p) in projected solid angle, on sub x sub points.
double binMean(double l0, const glm::dvec3 &l1, int m, int p, int sub) {
    const double dPhi = kPi / kPhiBins;
    double sum = 0.0, weight = 0.0;
    for (int a = 0; a < sub; ++a)
        for (int q = 0; q < sub; ++q) {
            const double mu = (m + (a + 0.5) / sub) / kMuBins, phi = (p + (q + 0.5) / sub) * dPhi;
            const double s = std::sqrt(1.0 - mu * mu);
            sum += mu * lobeRadiance(l0, l1, glm::dvec3(s * std::cos(phi), s * std::sin(phi), mu));
            weight += mu;
        }
    return sum / weight;
}

const std::vector<PeakShape> &peakShapes() {
    static const std::vector<PeakShape> shapes = [] {
        constexpr int kSub = 8;
        const double dPhi = kPi / kPhiBins;
        std::vector<PeakShape> out;
        for (int i = 0; i < kPeakKs; ++i)
            for (int j = 0; j < kPeakElevations; ++j) {
                PeakShape shape{peakK(i), peakElevation(j), 0.0, {}};
                const glm::dvec3 l1 = 3.0 * shape.k * glm::dvec3(std::cos(shape.elevation), 0.0, std::sin(shape.elevation));
                double exitance = 0.0;  // over pi, of the lobe of l0 = 1
                for (int m = 0; m < kMuBins; ++m)
                    for (int p = 0; p < kPhiBins; ++p) {
                        const double mean = binMean(1.0, l1, m, p, kSub);
                        const double muLo = double(m) / kMuBins, muHi = double(m + 1) / kMuBins;
                        shape.bins.push_back(mean);
                        exitance += 2.0 * dPhi * 0.5 * (muHi * muHi - muLo * muLo) / kPi * mean;
                    }
                for (double &v : shape.bins) v /= exitance;
                shape.mean = 1.0 / exitance;
                out.push_back(std::move(shape));
            }
        return out;
    }();
    return shapes;
}

// The linear rests the fit under a low sun chooses from (restShapes), each as the grids render it: the broad lobe
// exitLobe fits to 1 + b (mu - 2/3) + c t . w (source_lobe.h), as bin means like the peaks'; b and c on a grid over
// the linear fits' range.
struct RestShape {
    double b = 0.0, c = 0.0;
    std::vector<double> bins;
};
constexpr int kRestBs = 73, kRestCs = 61;
double restB(int i) { return -3.2 + 0.05 * i; }
double restC(int j) { return -0.5 + 0.05 * j; }

// The rest 1 + b (mu - 2/3) + c t . w as its broad lobe renders it, over the bins; empty where it is negative over
// them (the lobe is fitted to the form cut at zero, and the cut light lost).
RestShape restShape(double b, double c) {
    constexpr int kSub = 4;
    const double dPhi = kPi / kPhiBins;
    RestShape shape{b, c, {}};
    const SourceLobe lobe = exitLobe(1.0 - 2.0 * b / 3.0, glm::dvec3(c, 0.0, b), glm::dvec3(0.0, 0.0, 1.0));
    for (int m = 0; m < kMuBins; ++m)
        for (int p = 0; p < kPhiBins; ++p) {
            const double muC = (m + 0.5) / kMuBins;
            if (1.0 + b * (muC - 2.0 / 3.0) + c * std::sqrt(1.0 - muC * muC) * std::cos((p + 0.5) * dPhi) < 0.0) return {};
            shape.bins.push_back(binMean(lobe.l0, lobe.l1, m, p, kSub));
        }
    return shape;
}

const std::vector<RestShape> &restShapes() {
    static const std::vector<RestShape> shapes = [] {
        std::vector<RestShape> out;
        for (int i = 0; i < kRestBs; ++i)
            for (int j = 0; j < kRestCs; ++j)
                if (RestShape shape = restShape(restB(i), restC(j)); !shape.bins.empty()) out.push_back(std::move(shape));
        return out;
    }();
    return shapes;
}

// The split as the grids render it (kRenderedRestMu0): share P + x Q, Q the rest's broad lobe (restShapes) and x its
// exitance (at most 1 - share), by weighted least squares in the relative error of a model of R / A (the bins'
// weights; then of the split found, once more), share and x in closed form for each peak and rest. At grazing exit
// (the first kGrazingExitBins, mu < 0.3) the split stays under `ceiling`: a ball's limb is seen there, whose curved
// rim returns less than a half-space and overshot already; with the exitance kept and no ceiling, the fit paid for
// the light from above with up to twice the half-space's forward grazing return (ball_grey 7.4 -> 7.9 %).
constexpr std::size_t kGrazingExitBins = 6 * kPhiBins;

// The peaks a sun of cosine mu0 may take: the axis under kMinPeakElevationDegrees only at grazing sun.
bool peakAllowed(const PeakShape &peak, double mu0) {
    return mu0 < kGrazingSunMu0 || peak.elevation >= kMinPeakElevationDegrees * kPi / 180.0;
}

// The bins' weights in the relative error of `model`: projected solid angle over its square (at least 0.05's).
std::vector<double> relativeWeights(const Reflection &r, const std::vector<double> &model) {
    std::vector<double> w(r.bins.size());
    for (std::size_t b = 0; b < w.size(); ++b) w[b] = r.bins[b].measure / std::max(0.05 * 0.05, model[b] * model[b]);
    return w;
}

// Share s of a peak P and exitance x of a rest Q closest to R in the weights, |R - s P - x Q|^2 from its sums
// (wRP = sum w R P, ...): the normal equations in (s, x); where x passes 1 - s, the least on x = 1 - s. None where
// the peak takes no light or the rest would be negative.
std::optional<std::pair<double, double>> shareAndRest(double wRP, double wPP, double wPQ, double wRQ, double wQQ) {
    const double det = wPP * wQQ - wPQ * wPQ;
    if (!(det > 0.0)) return std::nullopt;
    double s = (wRP * wQQ - wRQ * wPQ) / det, x = (wRQ * wPP - wRP * wPQ) / det;
    if (x > 1.0 - s) {
        const double ee = wPP - 2.0 * wPQ + wQQ;  // along P - Q from Q
        s = (wRP - wRQ - wPQ + wQQ) / ee, x = 1.0 - s;
    }
    if (!(s > 0.0) || x < 0.0) return std::nullopt;
    s = std::min(s, kMaxPeakShare);
    return std::make_pair(s, std::min(x, 1.0 - s));
}

// A rendered split: share of a peak (none: the rest alone) and the rest's exitance x.
struct RenderedSplit {
    const PeakShape *peak = nullptr;
    const RestShape *rest = nullptr;
    double share = 0.0, restExitance = 0.0;

    double bin(std::size_t b) const { return (peak ? share * peak->bins[b] : 0.0) + restExitance * rest->bins[b]; }
    SunPeak split() const {
        SunPeak out;
        out.b = rest->b, out.c = rest->c;
        if (peak) out.share = share, out.mean = share * peak->mean, out.k = peak->k, out.elevation = peak->elevation;
        out.rest = restExitance / (1.0 - share);
        return out;
    }
};

// The rendered split closest to R in the weights w among the peaks and rests, its grazing exits under `ceiling`;
// none if no split stays under it.
std::optional<RenderedSplit> closestRenderedSplit(const Reflection &r, const std::vector<double> &w,
                                                  const std::vector<double> &ceiling, double mu0) {
    const std::vector<PeakShape> &peaks = peakShapes();
    const std::vector<RestShape> &rests = restShapes();
    const std::size_t n = r.bins.size();
    double wRR = 0.0;
    for (std::size_t b = 0; b < n; ++b) wRR += w[b] * r.bins[b].R * r.bins[b].R;
    std::vector<double> wRQ(rests.size(), 0.0), wQQ(rests.size(), 0.0);
    for (std::size_t q = 0; q < rests.size(); ++q)
        for (std::size_t b = 0; b < n; ++b)
            wRQ[q] += w[b] * r.bins[b].R * rests[q].bins[b], wQQ[q] += w[b] * rests[q].bins[b] * rests[q].bins[b];
    double least = std::numeric_limits<double>::infinity();
    std::optional<RenderedSplit> best;
    // |R - s P - x Q|^2 in the weights, from the sums.
    auto consider = [&](const RenderedSplit &split, std::size_t q, double wRP, double wPP, double wPQ) {
        const double s = split.share, x = split.restExitance;
        const double e = wRR + s * s * wPP + x * x * wQQ[q] - 2.0 * s * wRP - 2.0 * x * wRQ[q] + 2.0 * s * x * wPQ;
        if (!(e < least)) return;
        for (std::size_t b = 0; b < kGrazingExitBins; ++b)
            if (split.bin(b) > ceiling[b]) return;
        least = e, best = split;
    };
    for (std::size_t q = 0; q < rests.size(); ++q)  // the rest alone
        consider({nullptr, &rests[q], 0.0, std::clamp(wRQ[q] / wQQ[q], 0.0, 1.0)}, q, 0.0, 0.0, 0.0);
    std::vector<double> wP(n);
    for (const PeakShape &peak : peaks) {
        if (!peakAllowed(peak, mu0)) continue;
        double wRP = 0.0, wPP = 0.0;
        for (std::size_t b = 0; b < n; ++b)
            wP[b] = w[b] * peak.bins[b], wRP += wP[b] * r.bins[b].R, wPP += wP[b] * peak.bins[b];
        for (std::size_t q = 0; q < rests.size(); ++q) {
            double wPQ = 0.0;
            for (std::size_t b = 0; b < n; ++b) wPQ += wP[b] * rests[q].bins[b];
            if (const auto sx = shareAndRest(wRP, wPP, wPQ, wRQ[q], wQQ[q]))
                consider({&peak, &rests[q], sx->first, sx->second}, q, wRP, wPP, wPQ);
        }
    }
    return best;
}

// Two passes: the weights from `model` (the linear split's), then from the split the first found. Where no split
// stays under the ceiling, the linear split's (first pass) or the first pass's.
SunPeak renderedSplit(const Reflection &r, const SunPeak &linear, std::vector<double> model,
                      const std::vector<double> &ceiling, double mu0) {
    SunPeak best = linear;
    for (int pass = 0; pass < 2; ++pass) {
        const std::optional<RenderedSplit> found = closestRenderedSplit(r, relativeWeights(r, model), ceiling, mu0);
        if (!found) break;
        best = found->split();
        for (std::size_t b = 0; b < r.bins.size(); ++b) model[b] = found->bin(b);
    }
    return best;
}
}  // namespace

SunLobe fitSunLobe(double g, double mu0, double y, long photons, std::uint64_t seed) {
    const Reflection r = halfSpaceReflection(g, mu0, y, photons, seed);
    SunLobe lobe;
    lobe.albedo = r.albedo;
    if (r.albedo <= 0.0) return lobe;
    const std::array<double, 2> x = fitLinear(r).first;
    lobe.b = x[0], lobe.c = x[1];
    lobe.a = 1.0 - 2.0 * lobe.b / 3.0;
    return lobe;
}

SunPeak fitSunPeak(double g, double mu0, double y, long photons, std::uint64_t seed) {
    const Reflection r = halfSpaceReflection(g, mu0, y, photons, seed);
    SunPeak best;
    if (r.albedo <= 0.0) return best;
    // R / A = share peak + (1 - share) (a + b (mu - 2/3) + c t . w), with a = 1: linear in share, (1 - share) b
    // and (1 - share) c for each peak (k, elevation), which a search over both chooses.
    auto [linear, least] = fitLinear(r);
    best.b = linear[0], best.c = linear[1];
    const PeakShape *bestPeak = nullptr;
    for (const PeakShape &peak : peakShapes()) {
        if (!peakAllowed(peak, mu0)) continue;
        std::array<double, 3> x{};
        const double error = fitRelative<3>(r, [&](std::size_t b) {
            const std::array<double, 2> linear = linearBasis(r.bins[b]);
            return std::array<double, 3>{peak.bins[b] - 1.0, linear[0], linear[1]};
        }, x);
        if (x[0] <= 0.0 || x[0] >= kMaxPeakShare || error >= least) continue;
        // The linear rest must not be negative anywhere (it would be cut at zero, and the light lost).
        const bool negative = std::any_of(r.bins.begin(), r.bins.end(), [&](const Reflection::Bin &bin) {
            return 1.0 - x[0] + x[1] * (bin.mu - 2.0 / 3.0) + x[2] * bin.forward < 0.0;
        });
        if (negative) continue;
        least = error;
        best.share = x[0], best.k = peak.k, best.elevation = peak.elevation;
        best.mean = x[0] * peak.mean;
        best.b = x[1] / (1.0 - x[0]), best.c = x[2] / (1.0 - x[0]);
        bestPeak = &peak;
    }
    if (mu0 >= kRenderedRestMu0) return best;
    // The linear split's model weighs the bins; the grazing exits stay under the half-space's return and a tenth (its
    // bins' noise) or the linear split's as rendered, whichever is more.
    const RestShape rest = restShape(best.b, best.c);
    std::vector<double> model(r.bins.size()), ceiling(r.bins.size());
    for (std::size_t b = 0; b < r.bins.size(); ++b) {
        const std::array<double, 2> f = linearBasis(r.bins[b]);
        const double peak = bestPeak ? best.share * bestPeak->bins[b] : 0.0;
        model[b] = peak + (1.0 - best.share) * (1.0 + best.b * f[0] + best.c * f[1]);
        ceiling[b] = std::max(1.1 * r.bins[b].R, rest.bins.empty() ? 0.0 : peak + (1.0 - best.share) * rest.bins[b]);
    }
    return renderedSplit(r, best, std::move(model), ceiling, mu0);
}

std::vector<LimbBin> limbDarkening(double g, double mu0, double y, long photons, std::uint64_t seed) {
    // The Monte Carlo in chunks of their own streams (about 1e5 photons each), summed as flux per bin (R A).
    const long chunks = std::max(1L, photons / 100000), perChunk = photons / chunks;
    std::vector<Reflection> parts(chunks);
    tbb::parallel_for(long(0), chunks, [&](long i) { parts[i] = halfSpaceReflection(g, mu0, y, perChunk, seed + i); });
    const SunLobe lobe = sunLobe(g, mu0, y);
    const SunPeak split = sunPeak(g, mu0, y, lobe);  // flat: the rest as the table has it (restKept at curvature 0)
    // The peaked lobe as the bake stores it (bake_surface_light: p1 = 3 k m mean(p0)), anisotropy k whatever its mean.
    const glm::dvec3 peak1 =
        3.0 * split.k * split.mean * glm::dvec3(std::cos(split.elevation), 0.0, std::sin(split.elevation));
    const SourceLobe rest = exitLobe(split.a(), glm::dvec3(split.c, 0.0, split.b), glm::dvec3(0.0, 0.0, 1.0));
    const double restExitance = (1.0 - split.share) * split.rest;
    constexpr int kSub = 8;
    std::vector<LimbBin> out;
    for (int m = 0; m < kMuBins; ++m)
        for (int p = 0; p < kPhiBins; ++p) {
            const std::size_t b = std::size_t(m) * kPhiBins + p;
            double returned = 0.0;  // R / A_table
            for (const Reflection &r : parts)
                if (!r.bins.empty()) returned += r.bins[b].R * r.albedo;
            returned /= double(chunks) * lobe.albedo;
            const double peak = split.share > 0.0 ? binMean(split.mean, peak1, m, p, kSub) : 0.0;
            const double broad = restExitance * binMean(rest.l0, rest.l1, m, p, kSub);
            out.push_back({(m + 0.5) / kMuBins, (p + 0.5) * kPi / kPhiBins,
                           broad > 0.0 ? (returned - peak) / broad : 1.0, peak, broad});
        }
    return out;
}

namespace {
// Trilinear in (y, g, mu0) between a table's entries of K values.
template <std::size_t K, typename Table>
std::array<double, K> interpolate(const Table &table, double g, double mu0, double y) {
    int iy, ig, im;
    double ty, tg, tm;
    locate(kSunLobeY, y, iy, ty);
    locate(kSunLobeG, g, ig, tg);
    locate(kSunLobeMu0, mu0, im, tm);
    std::array<double, K> v{};
    for (int dy = 0; dy < 2; ++dy)
        for (int dg = 0; dg < 2; ++dg)
            for (int dm = 0; dm < 2; ++dm) {
                const double w = (dy ? ty : 1 - ty) * (dg ? tg : 1 - tg) * (dm ? tm : 1 - tm);
                for (std::size_t k = 0; k < K; ++k) v[k] += w * table[iy + dy][ig + dg][im + dm][k];
            }
    return v;
}
}  // namespace

SunLobe sunLobe(double g, double mu0, double y) {
    const std::array<double, 3> v = interpolate<3>(kSunLobeTable, g, mu0, y);  // b, c, A
    SunLobe lobe;
    lobe.b = v[0], lobe.c = v[1], lobe.albedo = v[2];
    lobe.a = 1.0 - 2.0 * lobe.b / 3.0;
    return lobe;
}

double sphericalAlbedo(double g, double y) {
    constexpr int kNodes = 40;  // midpoint rule in mu (below the table's first node, 0.05, A is held there)
    double albedo = 0.0;
    for (int m = 0; m < kNodes; ++m) {
        const double mu = (m + 0.5) / kNodes;
        albedo += 2.0 * sunLobe(g, mu, y).albedo * mu / kNodes;
    }
    return albedo;
}

SunPeak sunPeak(double g, double mu0, double y, const SunLobe &lobe) {
    const std::array<double, 7> v = interpolate<7>(kSunPeakTable, g, mu0, y);
    SunPeak peak;
    peak.share = v[0], peak.mean = v[1], peak.k = v[2], peak.elevation = v[3], peak.b = v[4], peak.c = v[5];
    peak.rest = v[6];
    // Towards high sun the split gives way to the sun lobe alone (what the peak holds there is small and noisy).
    const double s = std::clamp((kPeakFadeEnd - mu0) / (kPeakFadeEnd - kPeakFadeStart), 0.0, 1.0);
    const double split = s * (1.0 - peak.share) * peak.rest, rest = split + 1.0 - s;  // the rests' exitances
    peak.b = (split * peak.b + (1.0 - s) * lobe.b) / rest;
    peak.c = (split * peak.c + (1.0 - s) * lobe.c) / rest;
    peak.share *= s, peak.mean *= s;
    peak.rest = rest / (1.0 - peak.share);
    return peak;
}

double restKept(const SunPeak &split, double curvaturePerVoxel) {
    return split.rest + (1.0 - split.rest) * std::clamp(curvaturePerVoxel * kRestKeptRadius, 0.0, 1.0);
}

}  // namespace firn
