#include "firn/geometry/orientation.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

namespace firn {

namespace {

constexpr std::uint32_t kEmpty = ~std::uint32_t(0);

// A position's bits, -0 read as +0: exact positions, equal as floats compare them.
struct PositionBits {
    std::uint32_t bits[3];
    explicit PositionBits(const glm::vec3 &p) {
        const glm::vec3 q = p + glm::vec3(0.0f);  // -0 + 0 = +0
        std::memcpy(bits, &q, sizeof bits);
    }
    bool operator==(const PositionBits &o) const { return std::memcmp(bits, o.bits, sizeof bits) == 0; }
    std::uint64_t hash() const {
        const std::uint64_t h = (std::uint64_t(bits[0]) * 0x9E3779B97F4A7C15ull) ^
                                (std::uint64_t(bits[1]) * 0xC2B2AE3D27D4EB4Full) ^
                                (std::uint64_t(bits[2]) * 0x165667B19E3779F9ull);
        return h ^ (h >> 29);
    }
};

// Vertex index -> index of the first vertex at exactly the same position (imports often split every face).
// Open addressing over a power-of-two table of vertex indices: a node-based map cost 5x as much on 1M triangles.
std::vector<std::uint32_t> weldedVertices(const TriangleMesh &mesh) {
    const std::size_t count = mesh.positions.size();
    std::size_t capacity = 16;
    while (capacity < 2 * count) capacity *= 2;
    std::vector<std::uint32_t> table(capacity, kEmpty);
    std::vector<std::uint32_t> welded(count);
    for (std::uint32_t v = 0; v < count; ++v) {
        const PositionBits key(mesh.positions[v]);
        std::size_t slot = key.hash() & (capacity - 1);
        while (table[slot] != kEmpty && !(PositionBits(mesh.positions[table[slot]]) == key))
            slot = (slot + 1) & (capacity - 1);
        if (table[slot] == kEmpty) table[slot] = v;
        welded[v] = table[slot];
    }
    return welded;
}

// The triangles around each welded vertex, in compressed rows: around(v) = ids[first[v] .. first[v + 1]).
struct TrianglesAround {
    std::vector<std::size_t> first;  // offsets into ids (3 per triangle): past 32 bits beyond 1.4 G triangles
    std::vector<std::uint32_t> ids;
    TrianglesAround(const TriangleMesh &mesh, const std::vector<std::uint32_t> &welded)
        : first(welded.size() + 1, 0), ids(3 * mesh.triangleCount()) {
        for (const glm::uvec3 &t : mesh.triangles)
            for (int k = 0; k < 3; ++k) ++first[welded[t[k]] + 1];
        for (std::size_t v = 0; v < welded.size(); ++v) first[v + 1] += first[v];
        std::vector<std::size_t> next(first.begin(), first.end() - 1);
        for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t)
            for (int k = 0; k < 3; ++k) ids[next[welded[mesh.triangles[t][k]]]++] = t;
    }
};

}  // namespace

OpenSurfaceTurns findOpenSurfaceTurns(const TriangleMesh &mesh, const glm::vec3 &up) {
    const std::size_t n = mesh.triangleCount();
    std::vector<char> down(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t t) { down[t] = glm::dot(mesh.crossNormal(t), up) < 0.0f; });
    // Only components with a triangle facing away from `up` can change: found by walking out from those
    // triangles, so a terrain or floor that faces up everywhere is never walked.
    std::size_t firstDown = 0;
    while (firstDown < n && !down[firstDown]) ++firstDown;
    OpenSurfaceTurns turns;
    if (firstDown == n) return turns;
    const std::vector<std::uint32_t> welded = weldedVertices(mesh);
    const TrianglesAround around(mesh, welded);
    const auto corner = [&](std::uint32_t t, int k) { return welded[mesh.triangles[t][k]]; };
    const auto hasCorner = [&](std::uint32_t t, std::uint32_t v) {
        return corner(t, 0) == v || corner(t, 1) == v || corner(t, 2) == v;
    };

    std::vector<char> reached(n, 0);
    std::vector<std::uint32_t> component, frontier;
    for (std::size_t seed = firstDown; seed < n; ++seed) {
        if (!down[seed] || reached[seed]) continue;
        // The seed's edge-connected component; open if some edge belongs to no other triangle.
        component.clear();
        frontier.assign(1, std::uint32_t(seed));
        reached[seed] = 1;
        bool open = false;
        while (!frontier.empty()) {
            const std::uint32_t t = frontier.back();
            frontier.pop_back();
            component.push_back(t);
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t a = corner(t, k), b = corner(t, (k + 1) % 3);
                bool shared = false;
                for (std::size_t i = around.first[a]; i < around.first[a + 1]; ++i) {
                    const std::uint32_t u = around.ids[i];
                    if (u == t || !hasCorner(u, b)) continue;
                    shared = true;
                    if (!reached[u]) reached[u] = 1, frontier.push_back(u);
                }
                open = open || !shared;
            }
        }
        if (!open) continue;
        for (std::uint32_t t : component)
            if (down[t]) turns.triangles.push_back(t);
        ++turns.changed.surfaces;
    }
    std::sort(turns.triangles.begin(), turns.triangles.end());
    turns.changed.triangles = turns.triangles.size();
    return turns;
}

void applyTurns(TriangleMesh &mesh, const OpenSurfaceTurns &turns) {
    for (std::uint32_t t : turns.triangles) std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
}

Reorientation orientOpenSurfaces(TriangleMesh &mesh, const glm::vec3 &up) {
    const OpenSurfaceTurns turns = findOpenSurfaceTurns(mesh, up);
    applyTurns(mesh, turns);
    return turns.changed;
}

}  // namespace firn
