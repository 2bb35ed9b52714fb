#include "firn/transport/bounce_tail.h"

#include <algorithm>
#include <unordered_map>
#include <vector>

namespace firn {

void addBounceTail(const SnowTopology &topo, const SurfaceValues<glm::vec3> *older, const SurfaceValues<glm::vec3> &before,
                   SurfaceValues<glm::vec3> &last) {
    const auto olderAt = [&](std::size_t i) { return older ? glm::dvec3((*older)[i]) : glm::dvec3(0.0); };
    // Per region: the area-weighted sums of the two last bounces over its patches.
    std::unordered_map<openvdb::Coord, std::size_t> regionOf;  // a region's block coordinate -> its index
    std::vector<glm::dvec3> previousBounce, lastBounce;
    std::vector<std::size_t> region(topo.size(), 0);
    for (std::size_t i = 0; i < topo.size(); ++i) {
        const double area = topo.patches[i].area;
        if (!(area > 0.0)) continue;
        const auto found = regionOf.emplace(topo.coord[i] >> kBounceRegionLog2, previousBounce.size());
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
