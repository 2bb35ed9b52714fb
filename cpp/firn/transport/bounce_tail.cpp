#include "firn/transport/bounce_tail.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace firn {

namespace {

// The block of kBounceRegionVoxels^3 voxels holding a voxel, as one key (21 bits per axis, wrapping: two blocks
// 2^21 blocks apart would share their ratio, far beyond any bake's extent).
std::uint64_t regionKey(const openvdb::Coord &c) {
    constexpr std::uint64_t mask = (1u << 21) - 1u;
    const auto axis = [&](int v) { return std::uint64_t(v >> kBounceRegionLog2) & mask; };
    return axis(c.x()) | axis(c.y()) << 21 | axis(c.z()) << 42;
}

}  // namespace

void addBounceTail(const SnowTopology &topo, const SurfaceValues<glm::vec3> *older, const SurfaceValues<glm::vec3> &before,
                   SurfaceValues<glm::vec3> &last) {
    const auto olderAt = [&](std::size_t i) { return older ? glm::dvec3((*older)[i]) : glm::dvec3(0.0); };
    // Per region: the area-weighted sums of the two last bounces over its patches.
    std::unordered_map<std::uint64_t, std::size_t> regionOf;
    std::vector<glm::dvec3> previousBounce, lastBounce;
    std::vector<std::size_t> region(topo.size(), 0);
    for (std::size_t i = 0; i < topo.size(); ++i) {
        const double area = topo.patches[i].area;
        if (!(area > 0.0)) continue;
        const auto found = regionOf.emplace(regionKey(topo.coord[i]), previousBounce.size());
        if (found.second) previousBounce.emplace_back(0.0), lastBounce.emplace_back(0.0);
        region[i] = found.first->second;
        previousBounce[region[i]] += area * (glm::dvec3(before[i]) - olderAt(i));
        lastBounce[region[i]] += area * glm::dvec3(last[i] - before[i]);
    }
    for (std::size_t i = 0; i < topo.size(); ++i) {
        if (!(topo.patches[i].area > 0.0)) continue;
        const glm::dvec3 &p = previousBounce[region[i]], &l = lastBounce[region[i]];
        for (int c = 0; c < 3; ++c) {
            const double r = p[c] > 0.0 ? std::clamp(l[c] / p[c], 0.0, kMaxBounceShare) : 0.0;
            if (r > 0.0) last.surface(i)[c] += float(std::max(0.0f, last[i][c] - before[i][c]) * r / (1.0 - r));
        }
    }
}

}  // namespace firn
