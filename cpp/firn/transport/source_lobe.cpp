#include "firn/transport/source_lobe.h"

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

}  // namespace

double lobeRadiance(double l0, const glm::dvec3 &l1, const glm::dvec3 &w) {
    const double length = glm::length(l1);
    if (l0 <= 0.0 || length <= 0.0) return l0;
    return l0 * lobe(std::min(length / (3.0 * l0), kMaxLobeAnisotropy), glm::dot(w, l1) / length);
}

double peakRadiance(double p0, double p0Mean, const glm::dvec3 &p1, const glm::dvec3 &w) {
    return p0Mean > 0.0 ? p0 / p0Mean * lobeRadiance(p0Mean, p1, w) : 0.0;
}

glm::dvec3 peakRadiance(const glm::dvec3 &p0, const glm::dvec3 &p1, const glm::dvec3 &w) {
    const double mean = (p0.x + p0.y + p0.z) / 3.0;
    if (!(mean > 0.0)) return glm::dvec3(0.0);
    const double shape = lobeRadiance(mean, p1, w);
    return glm::dvec3(p0.x / mean * shape, p0.y / mean * shape, p0.z / mean * shape);
}

namespace {

// The fitted lobe of a normalized exit radiance L(w) = max(0, (1 - t) + t m . w) on the hemisphere around z,
// m = (sin alpha, 0, cos alpha): k, and l0 over (e0 + |e1|).
struct FittedLobe {
    double k = 0.0, scale = 0.0;
};

constexpr int kTableT = 41, kTableAlpha = 37, kNodesMu = 16, kNodesPhi = 16, kLobeSteps = 95;

FittedLobe fitLobe(double t, double alpha) {
    const glm::dvec3 m(std::sin(alpha), 0.0, std::cos(alpha));
    struct Node {
        double c, L, weight;  // cos to the axis, target radiance, projected solid angle
    };
    std::vector<Node> nodes;
    double exitance = 0.0;
    for (int i = 0; i < kNodesMu; ++i)
        for (int j = 0; j < kNodesPhi; ++j) {  // phi in [0, pi]: L and the lobe are symmetric about the (m, z) plane
            const double mu = (i + 0.5) / kNodesMu, phi = kPi * (j + 0.5) / kNodesPhi, s = std::sqrt(1.0 - mu * mu);
            const double c = glm::dot(m, glm::dvec3(s * std::cos(phi), s * std::sin(phi), mu));
            const double weight = mu / (kNodesMu * kNodesPhi);
            nodes.push_back({c, std::max(0.0, (1.0 - t) + t * c), weight});
            exitance += weight * ((1.0 - t) + t * c);  // the linear form's, negative parts included: its energy
        }
    if (exitance <= 0.0) return {};
    // Relative error, its denominator floored (at a tenth of the exitance) where L nears zero.
    const double floor2 = 0.01 * exitance * exitance;
    std::array<double, kNodesMu * kNodesPhi> lobes;  // the lobe at the nodes, evaluated once for both sums
    auto fit = [&](double k) {
        double flux = 0.0;
        for (std::size_t i = 0; i < nodes.size(); ++i) flux += nodes[i].weight * (lobes[i] = lobe(k, nodes[i].c));
        const double scale = exitance / flux;  // keeps the exitance
        double error = 0.0;
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            const double r = scale * lobes[i] - nodes[i].L;
            error += nodes[i].weight * r * r / (nodes[i].L * nodes[i].L + floor2);
        }
        return std::pair{error, scale};
    };
    // The best k on a grid of steps of 0.01, among lobes whose mean stays within the linear form's largest
    // value (1 here): a lobe pointing into the snow would otherwise hide most of its light in directions no
    // camera sees, and its large l0, interpolated with its neighbours' by the renderer, would shine.
    FittedLobe best;
    double least = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= kLobeSteps; ++i) {
        const double k = kMaxLobeAnisotropy * i / kLobeSteps;
        const auto [error, scale] = fit(k);
        if (scale <= 1.0 && error < least) least = error, best = {k, scale};
    }
    return best;
}

// Fitted on first use, in parallel (0.3 processor s): the bake's first exitLobe comes from a parallel loop, whose
// other threads, with a plain static, would wait idle on its guard (the car's bake: 0.3 s on one core); with
// collaborative_call_once they fit entries too. Each entry is its own fit: the same table on any thread count.
const std::array<FittedLobe, kTableT * kTableAlpha> &lobeTable() {
    static std::array<FittedLobe, kTableT * kTableAlpha> table;
    static tbb::collaborative_once_flag fitted;
    tbb::collaborative_call_once(fitted, [] {
        tbb::parallel_for(0, kTableT * kTableAlpha, [](int e) {
            const int i = e / kTableAlpha, j = e % kTableAlpha;
            table[e] = fitLobe(double(i) / (kTableT - 1), kPi * j / (kTableAlpha - 1));
        });
    });
    return table;
}

}  // namespace

SourceLobe exitLobe(double e0, const glm::dvec3 &e1, const glm::dvec3 &normal) {
    const double length = glm::length(e1);
    // Not a lobe: nothing leaves, or a value that is not a number would index the table anywhere.
    if (!(e0 > 0.0) || !std::isfinite(e0 + length)) return {};
    const glm::dvec3 m = length > 0.0 ? e1 / length : normal;
    const double t = length / (e0 + length) * (kTableT - 1);
    const double alpha = std::acos(std::clamp(glm::dot(m, normal), -1.0, 1.0)) / kPi * (kTableAlpha - 1);
    const int i = std::min(int(t), kTableT - 2), j = std::min(int(alpha), kTableAlpha - 2);
    const double u = t - i, v = alpha - j;
    const auto &table = lobeTable();
    auto at = [&](int di, int dj) { return table[(i + di) * kTableAlpha + j + dj]; };
    const double k = (1 - u) * ((1 - v) * at(0, 0).k + v * at(0, 1).k) + u * ((1 - v) * at(1, 0).k + v * at(1, 1).k);
    const double scale = (1 - u) * ((1 - v) * at(0, 0).scale + v * at(0, 1).scale) +
                         u * ((1 - v) * at(1, 0).scale + v * at(1, 1).scale);
    SourceLobe out;
    out.l0 = (e0 + length) * scale;
    out.l1 = 3.0 * k * out.l0 * m;
    return out;
}

}  // namespace firn
