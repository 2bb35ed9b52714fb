#include "firn/snow/snowfall.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/error.h"
#include "firn/util/random.h"

namespace firn {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSlideBand = 15.0 * kPi / 180.0;  // rad: snow thins to nothing over this much slope
constexpr float kMinCover = 0.01f;
const glm::vec3 kUp(0.0f, 0.0f, 1.0f);

// The plastic-number Kronecker sequence (Roberts 2018): low-discrepancy for any count.
constexpr double kR2a = 0.7548776662466927, kR2b = 0.5698402909980532;

double fract(double x) { return x - std::floor(x); }

// Orthonormal frame around a unit axis (Duff et al. 2017).
void basis(const glm::vec3 &n, glm::vec3 &t, glm::vec3 &b) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float c = n.x * n.y * a;
    t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = glm::vec3(c, sign + n.y * n.y * a, -n.y);
}

// Number of sites on a triangle expecting `expected` (area/spacing^2, within the budget): rounded at random.
std::size_t siteCount(double expected, Rng &rng) {
    const double whole = std::floor(expected);
    return static_cast<std::size_t>(whole) + (rng.uniform() < expected - whole ? 1 : 0);
}

struct TriangleSetup {
    glm::vec3 normal;
    float cover;  // slope part only
};

TriangleSetup setupTriangle(const glm::vec3 &cross, double maxSlope) {
    const glm::vec3 n = glm::normalize(cross);
    const double cosUp = std::clamp(static_cast<double>(glm::dot(n, kUp)), -1.0, 1.0);
    return {n, static_cast<float>(slopeCover(std::acos(cosUp), maxSlope))};
}

// Whether setupTriangle(cross, maxSlope).cover is not <= 0, as it would say, but without its acos and cos
// where the slope is clearly below or above maxSlope (1e-6 in cosine: far wider than their rounding, and a
// cover surely above zero there). Most triangles of a large scene are one or the other.
class SnowSlope {
  public:
    explicit SnowSlope(double maxSlope) : maxSlope_(maxSlope), cosMax_(std::cos(maxSlope)) {}
    bool holds(const glm::vec3 &cross) const {
        constexpr double kSure = 1e-6;
        const double cosUp = static_cast<double>(glm::dot(glm::normalize(cross), kUp));
        if (cosUp >= std::max(cosMax_, 0.0) + kSure) return true;
        if (cosUp <= cosMax_ - kSure) return false;
        return !(setupTriangle(cross, maxSlope_).cover <= 0.0f);  // near maxSlope, or not finite
    }

  private:
    double maxSlope_, cosMax_;
};

void checkSiteBudget(double sites, double maxSites) {
    if (sites <= maxSites) return;
    std::ostringstream msg;
    msg.precision(3);
    msg << "snow would land on about " << sites << " sites, over the budget of " << maxSites
        << ": use a larger spacing, fewer or smaller targets (or raise the voxel budget in Firn's preferences)";
    throw BudgetExceeded(msg.str());
}

void checkDepthWeights(const std::vector<float> &weights, std::size_t vertexCount) {
    if (weights.empty()) return;
    if (weights.size() != vertexCount)
        throw InvalidArgument("depth weights: " + std::to_string(weights.size()) + " for " +
                              std::to_string(vertexCount) + " target vertices");
    for (std::size_t i = 0; i < weights.size(); ++i)
        if (!(weights[i] >= 0.0f && weights[i] <= 1.0f))
            throw InvalidArgument("depth weight of vertex " + std::to_string(i) + " must be between 0 and 1 (got " +
                                  std::to_string(weights[i]) + ")");
}

// A vertex weight linearly interpolated at barycentric coordinates `bary` of triangle t.
float weightAt(const TriangleMesh &mesh, const std::vector<float> &weights, std::size_t t, const glm::vec3 &bary) {
    const glm::uvec3 corners = mesh.triangles[t];
    return bary.x * weights[corners.x] + bary.y * weights[corners.y] + bary.z * weights[corners.z];
}

// A triangle's random stream, from its corners' positions in order: Blender hands a script-made mesh's triangles
// in an order that changes from one process to the next (the triangles and their corners the same), so a stream
// by index gave another snow (1,777,469 against 1,778,113 voxels on bench/snow_layer_bench.py's scene).
std::uint64_t triangleStream(const TriangleMesh &mesh, std::size_t t) {
    std::uint64_t stream = 0;
    for (int k = 0; k < 3; ++k) {
        const glm::vec3 p = mesh.vertex(t, k);
        stream = pointStream(p.x, p.y, p.z, stream);
    }
    return stream;
}

}  // namespace

double snowfallExposure(const glm::vec3 &origin, const glm::vec3 &normal, const RayCaster &occluders,
                        const SnowfallSettings &settings, double shiftU, double shiftV) {
    const glm::vec3 from = -glm::normalize(settings.direction);  // snow comes from this way
    glm::vec3 coneT, coneB;
    basis(from, coneT, coneB);
    const int rays = settings.spread > 0.0 ? std::max(1, settings.exposureRays) : 1;
    const double cosSpread = std::cos(settings.spread);
    int open = 0;
    for (int k = 0; k < rays; ++k) {
        const double cosTheta = 1.0 - fract(shiftU + k * kR2a) * (1.0 - cosSpread);
        const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
        const double phi = 2.0 * kPi * fract(shiftV + k * kR2b);
        const glm::vec3 dir = glm::normalize(from * float(cosTheta) + coneT * float(sinTheta * std::cos(phi)) +
                                             coneB * float(sinTheta * std::sin(phi)));
        if (glm::dot(dir, normal) > 0.0f && !occluders.occluded(origin, dir)) ++open;
    }
    return double(open) / double(rays);
}

double slopeCover(double slope, double maxSlope) {
    if (slope >= maxSlope) return 0.0;
    const double band = std::min(kSlideBand, maxSlope);
    const double x = std::clamp((maxSlope - slope) / band, 0.0, 1.0);
    return std::cos(slope) * x * x * (3.0 - 2.0 * x);  // smoothstep
}

std::vector<LandingSite> findLandingSites(const TriangleMesh &targets, const RayCaster &occluders,
                                          const SnowfallSettings &settings, const SubProgress &progress,
                                          const std::vector<float> &depthWeights) {
    if (!(settings.spacing > 0.0)) throw InvalidArgument("snow spacing must be positive");
    checkDepthWeights(depthWeights, targets.positions.size());
    if (!std::isfinite(glm::normalize(settings.direction).x))
        throw InvalidArgument("snowfall direction must be a non-zero vector");
    const std::size_t nTri = targets.triangleCount();

    // Pass 1: how many sites each triangle gets (seeded per triangle by its corners: independent of threads and of
    // the triangles' order), refused before anything is placed when a huge surface or a tiny spacing would make
    // more than the budget allows.
    std::vector<double> expected(nTri, 0.0);
    std::vector<std::size_t> offsets(nTri + 1, 0);
    const SnowSlope snowSlope(settings.maxSlope);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nTri), [&](const tbb::blocked_range<std::size_t> &r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            const glm::vec3 cross = targets.crossNormal(t);
            if (!snowSlope.holds(cross)) continue;
            expected[t] = 0.5 * glm::length(cross) / (settings.spacing * settings.spacing);  // area / spacing^2
            // Drawn here, with the corners just read (2 ms per million triangles); a count over the budget, or
            // not finite, is left out: the check below refuses it.
            if (!(expected[t] <= settings.maxSites)) continue;
            Rng rng(settings.seed, triangleStream(targets, t));
            offsets[t + 1] = siteCount(expected[t], rng);
        }
    });
    checkSiteBudget(std::accumulate(expected.begin(), expected.end(), 0.0), settings.maxSites);
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    std::vector<LandingSite> sites(offsets.back());
    progress.report(0.05);

    // Pass 2: place the sites and cast their exposure rays.
    const float eps = static_cast<float>(1e-4 * settings.spacing) + 1e-5f;  // m, leaves the surface
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nTri, 256), [&](const tbb::blocked_range<std::size_t> &r) {
        progress.throwIfCancelled();
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            const std::size_t count = offsets[t + 1] - offsets[t];
            if (count == 0) continue;
            const TriangleSetup tri = setupTriangle(targets.crossNormal(t), settings.maxSlope);
            Rng rng(settings.seed, triangleStream(targets, t));
            siteCount(expected[t], rng);  // replay pass 1's draw
            const double shiftU = rng.uniform(), shiftV = rng.uniform();
            const glm::vec3 a = targets.vertex(t, 0), b = targets.vertex(t, 1), c = targets.vertex(t, 2);
            for (std::size_t i = 0; i < count; ++i) {
                // Square to triangle with the square-root map, which keeps the sequence stratified.
                const double su = std::sqrt(fract(shiftU + (i + 1) * kR2a)), v = fract(shiftV + (i + 1) * kR2b);
                const glm::vec3 bary(float(1.0 - su), float(su * (1.0 - v)), float(su * v));
                const glm::vec3 p = a * bary.x + b * bary.y + c * bary.z;
                const glm::vec3 origin = p + tri.normal * eps;
                const double rayU = rng.uniform(), rayV = rng.uniform();
                const double open = snowfallExposure(origin, tri.normal, occluders, settings, rayU, rayV);
                const float weight = depthWeights.empty() ? 1.0f : weightAt(targets, depthWeights, t, bary);
                sites[offsets[t] + i] = {p, tri.normal, weight * tri.cover * float(open)};
            }
        }
        progress.report(0.05 + 0.95 * double(done += r.size()) / double(nTri));
    });
    sites.erase(std::remove_if(sites.begin(), sites.end(), [](const LandingSite &s) { return s.cover < kMinCover; }),
                sites.end());
    return sites;
}

}  // namespace firn
