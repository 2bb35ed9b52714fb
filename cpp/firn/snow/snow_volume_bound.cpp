#include "firn/snow/snow_volume_bound.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr float kLift = 1e-4f;  // m: sample points leave the surface before their ray

// Slope cover (snowfall.h) of each triangle times its area (m^2): where snow can lie, and how deep.
std::vector<double> coveredAreas(const TriangleMesh &targets, double maxSlope) {
    std::vector<double> covered(targets.triangleCount(), 0.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, covered.size()), [&](const tbb::blocked_range<std::size_t> &r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            const glm::vec3 cross = targets.crossNormal(t);
            const glm::dvec3 n = glm::normalize(glm::dvec3(cross));
            if (!std::isfinite(n.z)) continue;  // degenerate: no area
            covered[t] = 0.5 * glm::length(cross) * slopeCover(std::acos(std::clamp(n.z, -1.0, 1.0)), maxSlope);
        }
    });
    return covered;
}

// Fraction of the covered area (weighted by cover) that one ray into the snowfall cone finds open, with its
// standard error.
std::pair<double, double> openFraction(const TriangleMesh &targets, const RayCaster &shelter,
                                       const SnowfallSettings &snowfall, const std::vector<double> &cdf, int samples) {
    const glm::dvec3 from = -glm::normalize(glm::dvec3(snowfall.direction));
    const double cosSpread = std::cos(snowfall.spread);
    Rng rng(snowfall.seed, 0x5B0DULL);
    int open = 0;
    for (int i = 0; i < samples; ++i) {
        const double pick = rng.uniform() * cdf.back();
        const std::size_t t = std::size_t(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin());
        const double su = std::sqrt(rng.uniform()), v = rng.uniform();
        const glm::vec3 n = glm::normalize(targets.crossNormal(t));
        const glm::vec3 p = targets.vertex(t, 0) * float(1.0 - su) + targets.vertex(t, 1) * float(su * (1.0 - v)) +
                            targets.vertex(t, 2) * float(su * v) + n * kLift;
        const glm::dvec3 d = sampleUniformCone(from, cosSpread, rng.uniform(), rng.uniform());
        if (glm::dot(glm::vec3(d), n) > 0.0f && !shelter.occluded(p, glm::vec3(d))) ++open;
    }
    const double f = double(open) / samples;
    return {f, std::sqrt(std::max(f * (1.0 - f), 1.0 / samples) / samples)};
}

}  // namespace

double snowVoxelLowerBound(const TriangleMesh &targets, const RayCaster &shelter, const SnowfallSettings &snowfall,
                           double depth, double voxelSize, int samples) {
    std::vector<double> cdf = coveredAreas(targets, snowfall.maxSlope);  // summed in place
    double sum = 0.0;
    for (double &c : cdf) c = sum += c;
    if (!(sum > 0.0)) return 0.0;
    const auto [f, error] = openFraction(targets, shelter, snowfall, cdf, samples);
    return sum * std::max(0.0, f - 3.0 * error) * depth / (voxelSize * voxelSize * voxelSize);
}

}  // namespace firn
