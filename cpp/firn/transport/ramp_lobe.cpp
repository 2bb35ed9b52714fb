#include "firn/transport/ramp_lobe.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/collaborative_call_once.h>
#include <tbb/parallel_for.h>

#include "firn/util/sampling.h"

namespace firn {

namespace {

// 4 pi HG(k, cos): mean 1 over the sphere.
double lobe(double k, double cos) {
    const double d = 1.0 + k * k - 2.0 * k * cos;
    return (1.0 - k * k) / (d * std::sqrt(d));
}

// J for a face lobe of mean 1 and anisotropy kFace about m = (sin beta, 0, cos beta), n = z, albedo 1: its mean
// (`share`: the face lobe's mean over the hemisphere), its axis at angle `gamma` from n towards m, its fitted k.
struct RampFit {
    double share = 0.0, gamma = 0.0, k = 0.0;
};

constexpr int kTableK = 20, kTableBeta = 19, kTableG = 39;  // kFace 0..0.95, beta 0..pi, g -0.95..0.95
constexpr double kGStep = 0.05;
constexpr int kHemiMu = 16, kHemiPhi = 32, kSphereMu = 24, kSpherePhi = 12, kLobeSteps = 95;

RampFit fitRamp(double kFace, double beta, double g) {
    const glm::dvec3 m(std::sin(beta), 0.0, std::cos(beta));
    // The face's light on the outward hemisphere (midpoint nodes in mu and phi): direction and radiance times dw'.
    std::vector<std::pair<glm::dvec3, double>> face;
    face.reserve(kHemiMu * kHemiPhi);
    for (int i = 0; i < kHemiMu; ++i)
        for (int j = 0; j < kHemiPhi; ++j) {
            const double mu = (i + 0.5) / kHemiMu, phi = 2.0 * kPi * (j + 0.5) / kHemiPhi, s = std::sqrt(1 - mu * mu);
            const glm::dvec3 w(s * std::cos(phi), s * std::sin(phi), mu);
            face.push_back({w, lobe(kFace, glm::dot(m, w)) * 2.0 * kPi / (kHemiMu * kHemiPhi)});
        }
    // J over the sphere, phi in [0, pi] (J is symmetric about the (m, n) plane): direction, J, dw (twice: both sides).
    struct Node {
        glm::dvec3 w;
        double J, weight;
    };
    std::vector<Node> nodes;
    nodes.reserve(kSphereMu * kSpherePhi);
    double mean = 0.0;
    glm::dvec3 moment(0.0);
    for (int i = 0; i < kSphereMu; ++i)
        for (int j = 0; j < kSpherePhi; ++j) {
            const double mu = -1.0 + 2.0 * (i + 0.5) / kSphereMu, phi = kPi * (j + 0.5) / kSpherePhi;
            const double s = std::sqrt(1.0 - mu * mu);
            const glm::dvec3 w(s * std::cos(phi), s * std::sin(phi), mu);
            double J = 0.0;
            for (const auto &[v, L] : face) J += L * henyeyGreenstein(glm::dot(w, v), g);
            const double weight = 4.0 * kPi / (kSphereMu * kSpherePhi);
            nodes.push_back({w, J, weight});
            mean += weight * J, moment += weight * J * glm::dvec3(w.x, 0.0, w.z);
        }
    mean /= 4.0 * kPi;
    if (!(mean > 0.0)) return {};
    RampFit fit{mean, std::atan2(moment.x, moment.z), 0.0};
    const glm::dvec3 axis(std::sin(fit.gamma), 0.0, std::cos(fit.gamma));
    double least = std::numeric_limits<double>::infinity();
    for (int s = 0; s <= kLobeSteps; ++s) {
        const double k = kMaxLobeAnisotropy * s / kLobeSteps;
        double error = 0.0;
        for (const Node &n : nodes) {
            const double r = mean * lobe(k, glm::dot(axis, n.w)) - n.J;
            error += n.weight * r * r;
        }
        if (error < least) least = error, fit.k = k;
    }
    return fit;
}

// One g's part of the table, fitted on its first use, in parallel (exitLobe's table's way: collaborative_call_once, so
// a parallel loop's other threads fit entries too instead of waiting). Each entry its own fit: the same on any thread
// count.
const std::array<RampFit, kTableK * kTableBeta> &tableForG(int gi) {
    static std::array<std::array<RampFit, kTableK * kTableBeta>, kTableG> tables;
    static std::array<tbb::collaborative_once_flag, kTableG> fitted;
    tbb::collaborative_call_once(fitted[gi], [gi] {
        tbb::parallel_for(0, kTableK * kTableBeta, [gi](int e) {
            const int i = e / kTableBeta, j = e % kTableBeta;
            tables[gi][e] = fitRamp(kMaxLobeAnisotropy * i / (kTableK - 1), kPi * j / (kTableBeta - 1),
                                    -0.95 + kGStep * gi);
        });
    });
    return tables[gi];
}

}  // namespace

SourceLobe rampLobe(double l0, const glm::dvec3 &l1, const glm::dvec3 &normal, double g, double albedo) {
    if (l0 <= 0.0) return {};
    const double length = glm::length(l1);
    const glm::dvec3 m = length > 0.0 ? l1 / length : normal;
    const double kFace = std::min(length / (3.0 * l0), kMaxLobeAnisotropy);
    const double cosBeta = std::clamp(glm::dot(m, normal), -1.0, 1.0);
    const double x = kFace / kMaxLobeAnisotropy * (kTableK - 1), y = std::acos(cosBeta) / kPi * (kTableBeta - 1);
    const double z = (std::clamp(g, -0.95, 0.95) + 0.95) / kGStep;
    const int i = std::min(int(x), kTableK - 2), j = std::min(int(y), kTableBeta - 2), q = std::min(int(z), kTableG - 2);
    const double u = x - i, v = y - j, t = z - q;
    RampFit fit;
    for (int dq = 0; dq < 2; ++dq) {
        const auto &table = tableForG(q + dq);
        for (int di = 0; di < 2; ++di)
            for (int dj = 0; dj < 2; ++dj) {
                const RampFit &e = table[(i + di) * kTableBeta + j + dj];
                const double weight = (dq ? t : 1 - t) * (di ? u : 1 - u) * (dj ? v : 1 - v);
                fit.share += weight * e.share, fit.gamma += weight * e.gamma, fit.k += weight * e.k;
            }
    }
    // The axis in the plane of n and m, gamma from n towards m.
    const glm::dvec3 across = m - cosBeta * normal;
    const double acrossLength = glm::length(across);
    const glm::dvec3 side = acrossLength > 1e-9 ? across / acrossLength : glm::dvec3(0.0);
    SourceLobe out;
    out.l0 = albedo * fit.share * l0;
    out.l1 = 3.0 * fit.k * out.l0 * (std::cos(fit.gamma) * normal + std::sin(fit.gamma) * side);
    return out;
}

}  // namespace firn
