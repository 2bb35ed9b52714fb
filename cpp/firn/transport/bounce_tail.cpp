#include "firn/transport/bounce_tail.h"

#include <algorithm>

namespace firn {

void addBounceTail(const SnowTopology &topo, const SurfaceValues<glm::vec3> *older, const SurfaceValues<glm::vec3> &before,
                   SurfaceValues<glm::vec3> &last) {
    const auto olderAt = [&](std::size_t i) { return older ? glm::dvec3((*older)[i]) : glm::dvec3(0.0); };
    glm::dvec3 previousBounce(0.0), lastBounce(0.0);
    for (std::size_t i = 0; i < topo.size(); ++i) {
        const double area = topo.patches[i].area;
        if (!(area > 0.0)) continue;
        previousBounce += area * (glm::dvec3(before[i]) - olderAt(i)), lastBounce += area * glm::dvec3(last[i] - before[i]);
    }
    for (int c = 0; c < 3; ++c) {
        const double r = previousBounce[c] > 0.0 ? std::clamp(lastBounce[c] / previousBounce[c], 0.0, kMaxBounceShare) : 0.0;
        if (!(r > 0.0)) continue;
        for (std::size_t i = 0; i < topo.size(); ++i)
            if (topo.patches[i].area > 0.0)
                last.surface(i)[c] += float(std::max(0.0f, last[i][c] - before[i][c]) * r / (1.0 - r));
    }
}

}  // namespace firn
