#include "firn/geometry/orientation.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <unordered_map>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

namespace firn {

namespace {

struct PositionHash {
    std::size_t operator()(const glm::vec3 &p) const {
        std::uint32_t bits[3];
        std::memcpy(bits, &p, sizeof bits);
        return (std::size_t(bits[0]) * 73856093u) ^ (std::size_t(bits[1]) * 19349663u) ^
               (std::size_t(bits[2]) * 83492791u);
    }
};

// Vertex index -> index of the first vertex at exactly the same position (imports often split every face).
std::vector<unsigned> weldedVertices(const TriangleMesh &mesh) {
    std::unordered_map<glm::vec3, unsigned, PositionHash> first;
    first.reserve(mesh.positions.size());
    std::vector<unsigned> welded(mesh.positions.size());
    for (unsigned v = 0; v < mesh.positions.size(); ++v)
        welded[v] = first.emplace(mesh.positions[v], v).first->second;
    return welded;
}

// Union-find over triangles.
struct Components {
    std::vector<std::size_t> parent;
    explicit Components(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), std::size_t(0)); }
    std::size_t root(std::size_t t) {
        while (parent[t] != t) t = parent[t] = parent[parent[t]];
        return t;
    }
    void join(std::size_t a, std::size_t b) { parent[root(a)] = root(b); }
};

struct EdgeUse {
    std::uint64_t edge;  // welded endpoints, smaller first
    std::size_t triangle;
    bool operator<(const EdgeUse &o) const { return edge < o.edge || (edge == o.edge && triangle < o.triangle); }
};

}  // namespace

Reorientation orientOpenSurfaces(TriangleMesh &mesh, const glm::vec3 &up) {
    const std::size_t n = mesh.triangleCount();
    // Nothing faces away from `up` (a terrain, a floor): nothing to turn, and no need to find the open surfaces.
    const bool anyDown = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n), false,
        [&](const tbb::blocked_range<std::size_t> &r, bool found) {
            for (std::size_t t = r.begin(); t != r.end() && !found; ++t) found = glm::dot(mesh.crossNormal(t), up) < 0.0f;
            return found;
        },
        [](bool a, bool b) { return a || b; });
    if (!anyDown) return {};
    const std::vector<unsigned> welded = weldedVertices(mesh);
    std::vector<EdgeUse> uses;
    uses.reserve(3 * n);
    for (std::size_t t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k) {
            const std::uint64_t a = welded[mesh.triangles[t][k]], b = welded[mesh.triangles[t][(k + 1) % 3]];
            uses.push_back({std::min(a, b) << 32 | std::max(a, b), t});
        }
    tbb::parallel_sort(uses.begin(), uses.end());

    Components components(n);
    std::vector<std::size_t> boundaryTriangles;  // triangles with an edge no other triangle shares
    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i + 1;
        for (; j < uses.size() && uses[j].edge == uses[i].edge; ++j) components.join(uses[i].triangle, uses[j].triangle);
        if (j - i == 1) boundaryTriangles.push_back(uses[i].triangle);
        i = j;
    }
    std::vector<char> open(n, 0);
    for (std::size_t t : boundaryTriangles) open[components.root(t)] = 1;

    Reorientation changed;
    std::vector<char> turned(n, 0);  // per component root
    for (std::size_t t = 0; t < n; ++t) {
        const std::size_t root = components.root(t);
        if (!open[root] || glm::dot(mesh.crossNormal(t), up) >= 0.0f) continue;
        std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
        ++changed.triangles;
        if (!turned[root]) turned[root] = 1, ++changed.surfaces;
    }
    return changed;
}

}  // namespace firn
