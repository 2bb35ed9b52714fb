#include "firn/transport/traced_source.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "firn/util/cholesky.h"
#include "firn/util/color.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

// Two Henyey-Greenstein lobes with the Legendre moments a0..a3 of an axially symmetric source (a_n = sum of
// w k^n over the lobes): the nodes k are the roots of x^2 + c1 x + c0 with a_(n+2) + c1 a_(n+1) + c0 a_n = 0
// (Prony's method; exact for two lobes). None where the moments are no such pair's.
struct LobePair {
    double kPeak, kBroad;  // kPeak > kBroad
};
std::optional<LobePair> lobePair(double a0, double a1, double a2, double a3) {
    const double det = a1 * a1 - a0 * a2;
    if (!(std::abs(det) > 1e-9 * a0 * a0)) return std::nullopt;
    const double c1 = (a0 * a3 - a1 * a2) / det, c0 = (a2 * a2 - a1 * a3) / det;
    const double disc = c1 * c1 - 4.0 * c0;
    if (!(disc >= 0.0)) return std::nullopt;
    const double x1 = 0.5 * (-c1 + std::sqrt(disc)), x2 = 0.5 * (-c1 - std::sqrt(disc));
    if (!(x1 > x2 && x1 <= 1.0 && x2 >= -kMaxLobeAnisotropy)) return std::nullopt;
    const double w1 = (a1 - x2 * a0) / (x1 - x2);
    if (!(w1 >= 0.0 && w1 <= a0)) return std::nullopt;
    return LobePair{x1, x2};
}

// The two lobes fitted by direction (fitByDirection), grey: the peaked lobe's mean and anisotropy k
// about the beams' axis, and the broad lobe's linear form l0 + l1 . w.
struct DirectionFit {
    double peak = 0.0, k = 0.0, l0 = 0.0;
    glm::dvec3 l1{0.0};
    double error = std::numeric_limits<double>::infinity();  // weighted squared misfit
};

// The lobes with the peaked one's anisotropy k (none: k < 0) fitted to the gathered source S.toward by weighted
// least squares: linear in the peak's mean and the broad lobe's l0 and l1.
DirectionFit fitAtK(const SourceEstimate &S, const SourceDirections &directions, const glm::dvec3 &m, double k,
                    const DirectionWeights &weights) {
    constexpr int n = 5;
    std::array<double, n * n> A{};  // row-major, the lower triangle
    std::array<double, n> b{};
    std::array<std::array<double, n>, kSourceDirections> basis;
    for (int j = 0; j < kSourceDirections; ++j) {
        const glm::dvec3 &w = directions[j];
        basis[j] = {k >= 0.0 ? 4.0 * kPi * henyeyGreenstein(glm::dot(w, m), k) : 0.0, 1.0, w.x, w.y, w.z};
        for (int r = 0; r < n; ++r) {
            b[r] += weights[j] * basis[j][r] * S.toward[j];
            for (int c = 0; c <= r; ++c) A[r * n + c] += weights[j] * basis[j][r] * basis[j][c];
        }
    }
    if (k < 0.0) A[0] = 1.0;  // no peak: its mean held at 0
    DirectionFit out;
    if (!solveSymmetric(A.data(), n, b.data(), 1e-12 * (1.0 + std::abs(A[0]))) || b[0] < 0.0 || b[1] <= 0.0) return out;
    out.peak = b[0], out.k = std::max(k, 0.0), out.l0 = b[1], out.l1 = glm::dvec3(b[2], b[3], b[4]);
    out.error = 0.0;
    for (int j = 0; j < kSourceDirections; ++j) {
        double model = 0.0;
        for (int r = 0; r < n; ++r) model += basis[j][r] * b[r];
        out.error += weights[j] * (model - S.toward[j]) * (model - S.toward[j]);
    }
    return out;
}

// The grey radiance a source's two lobes show towards w (source_lobe.h).
double greyRadiance(const Source &S, const glm::dvec3 &w) {
    const double peakMean = channelMean(S.peak0);
    double sum = 0.0;
    for (int c = 0; c < 3; ++c)
        sum += lobeRadiance(S.l0[c], glm::dvec3(S.l1[c]), w) + peakRadiance(S.peak0[c], peakMean, glm::dvec3(S.peak1), w);
    return sum / 3.0;
}

}  // namespace

void capBroad(BroadLobe &S) {
    for (int c = 0; c < 3; ++c) {
        const float length = glm::length(S.l1[c]), most = std::max(S.l0[c], 0.0f);
        if (length > most) S.l1[c] *= most / length;
    }
}

// At g 0.85 light scattered a few times is peaked too, and the peaked lobe takes it with the beams' single
// scattering (bench/bake_suite.py: ball_thin_forward 15.4 -> 9.1 %, per view -17, +17, -10, -16 % -> -3, +6, -0,
// -2 %). About the grey first moment's axis instead (tilted from the beams by the light leaving the object, and
// a beam's peak is sharp): +20 % seen against the sun. Per channel the two lobes keep that channel's mean and
// first moment along m; the broad lobe also takes the first moment across m. Where the moments are no pair's
// (or no beam reaches the voxel), the beams' single scattering alone is the peaked lobe (k = g) and the rest the
// broad one.
Source tracedSourceByMoments(const SourceEstimate &S, double g) {
    Source out;
    const double a0 = channelMean(S.l0);
    const glm::dvec3 first = (S.l1[0] + S.l1[1] + S.l1[2]) / 9.0, beamFirst = S.beamL1[0] + S.beamL1[1] + S.beamL1[2];
    const glm::dvec3 m = glm::length(beamFirst) > 0.0 ? glm::normalize(beamFirst) : glm::dvec3(0.0);
    const double a1 = glm::dot(first, m);  // a0 k along m
    if (g > 0.0 && a0 > 0.0 && a1 > 0.0) {
        // The arriving light's mean(l0) E[(t.m)^n], then the source's Legendre moments (g^n of the light's).
        // a3 = g^3 (5 t3 - 3 t1) / 2 with t1 = a1 / g, written without the ratio (it overflows for g near 0).
        const double t2 = glm::dot(m, S.second * m);
        const double t3 = m.x * glm::dot(m, S.third[0] * m) + m.y * glm::dot(m, S.third[1] * m) + m.z * glm::dot(m, S.third[2] * m);
        const double a2 = g * g * 0.5 * (3.0 * t2 - a0), a3 = g * g * 0.5 * (5.0 * g * t3 - 3.0 * a1);
        if (const std::optional<LobePair> pair = lobePair(a0, a1, a2, a3)) {
            const double kp = std::min(pair->kPeak, kMaxLobeAnisotropy), kb = pair->kBroad;
            glm::dvec3 peak;
            for (int c = 0; c < 3; ++c)
                peak[c] = std::clamp((glm::dot(S.l1[c], m) / 3.0 - kb * S.l0[c]) / (pair->kPeak - kb), 0.0, std::max(S.l0[c], 0.0));
            out.l0 = glm::vec3(S.l0 - peak);
            for (int c = 0; c < 3; ++c) out.l1[c] = glm::vec3(S.l1[c] - 3.0 * kp * peak[c] * m);
            out.addPeak(peak, kp, m);
            capBroad(out);
            return out;
        }
    }
    out.l0 = glm::vec3(S.l0 - S.beamL0);
    out.l1 = glm::mat3(S.l1 - S.beamL1);
    const glm::dvec3 peak = S.beamL0;
    const double peakMean = channelMean(peak);
    if (peakMean > 0.0 && g > 0.0)
        out.addPeak(peak, glm::length(beamFirst) / (9.0 * peakMean) * (crossingAnisotropy(g) / g), m);
    else
        out.peak0 = glm::vec3(peak);
    capBroad(out);
    return out;
}

std::optional<Source> fitByDirection(const SourceEstimate &S, const SourceDirections &directions,
                                    const DirectionWeights &visibility, const glm::dvec3 &m, double g,
                                    const Source &moments) {
    const double a0 = channelMean(S.l0);
    if (!(a0 > 0.0)) return std::nullopt;
    DirectionWeights weights;  // in units of a0 (the system's size independent of the light's)
    for (int j = 0; j < kSourceDirections; ++j) {
        const double model = std::max(greyRadiance(moments, directions[j]) / a0, 0.1);
        weights[j] = visibility[j] / (model * model);
    }
    // k ranked on the broad lobe's linear form, not the lobe the grids render of it (fitted in that shape: no
    // better, docs/bake.md, Method 3).
    std::vector<DirectionFit> fits{fitAtK(S, directions, m, -1.0, weights)};
    for (int i = 0; 0.5 + 0.01 * i <= std::min(g, kMaxLobeAnisotropy) + 1e-9; ++i)
        fits.push_back(fitAtK(S, directions, m, 0.5 + 0.01 * i, weights));
    const double best = std::min_element(fits.begin(), fits.end(), [](const DirectionFit &a, const DirectionFit &b) {
                            return a.error < b.error;
                        })->error;
    if (!std::isfinite(best)) return std::nullopt;
    // Not the best k but all of them, each weighted by its likelihood exp(-misfit / 2 sigma^2) (Akaike weights),
    // sigma^2 the best fit's misfit per degree of freedom: picking the least misfit among 37 k fits the noise of
    // 256 paths (spray_dense's thin voxels read 0.94 of a 4096-path bake towards the sun-lit views), the average
    // over the k the noise cannot tell apart does less so (docs/benchmarks.md, spray-air). Noise-free, the best.
    int seen = 0;  // directions the fit weighs
    for (int j = 0; j < kSourceDirections; ++j) seen += weights[j] > 1e-3;
    const double sigma2 = std::max(best / std::max(seen - 5, 1), std::numeric_limits<double>::min());
    const glm::dvec3 share = S.l0 / a0;  // each channel's of the grey mean
    Source out;
    double total = 0.0;
    for (const DirectionFit &fit : fits) {
        if (!std::isfinite(fit.error)) continue;
        const double w = std::exp(-0.5 * (fit.error - best) / sigma2);
        if (!(w > 0.0)) continue;
        Source one;
        one.l0 = glm::vec3(fit.l0 * share);
        for (int c = 0; c < 3; ++c) one.l1[c] = glm::vec3(fit.l1 * share[c]);
        if (fit.peak > 0.0) one.addPeak(fit.peak * share, fit.k, m);
        out.add(one, float(w));
        total += w;
    }
    out.divideBy(float(total));
    capBroad(out);
    return out;
}

Source tracedSourceByDirection(const SourceEstimate &S, const SourceDirections &directions,
                               const DirectionWeights &visibility, double g) {
    const Source moments = tracedSourceByMoments(S, g);
    const glm::dvec3 beamFirst = S.beamL1[0] + S.beamL1[1] + S.beamL1[2];
    if (!(glm::length(beamFirst) > 0.0)) return moments;
    return fitByDirection(S, directions, visibility, glm::normalize(beamFirst), g, moments).value_or(moments);
}

DirectionWeights visibilityFrom(const Medium &medium, Medium::ColumnMarcher &marcher, const openvdb::Coord &voxel,
                                const SourceDirections &directions) {
    constexpr double kMaxTau = 10.0;
    const double k = medium.optics().extinctionPerDensity;  // m^2/kg
    const glm::dvec3 centre = medium.voxelCentre(voxel);
    DirectionWeights out;
    for (int j = 0; j < kSourceDirections; ++j) {
        const glm::dvec3 origin = centre + 0.5 * medium.voxelSize() * directions[j];
        const double column = marcher.column(origin, directions[j], std::numeric_limits<double>::infinity(), kMaxTau / k);
        out[j] = std::exp(-k * column);  // column in kg/m^2
    }
    return out;
}

}  // namespace firn
