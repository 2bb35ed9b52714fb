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

// Walks the mesh's edge-connected components (vertices welded by exact position).
class ComponentWalk {
  public:
    explicit ComponentWalk(const TriangleMesh &mesh)
        : mesh_(mesh), welded_(weldedVertices(mesh)), around_(mesh, welded_), reached_(mesh.triangleCount(), 0) {}

    bool reached(std::uint32_t t) const { return reached_[t]; }

    // The component of `seed` (not reached before) into `component`; whether it is open: some edge belongs to no
    // other triangle.
    bool walk(std::uint32_t seed, std::vector<std::uint32_t> &component) {
        component.clear();
        frontier_.assign(1, seed);
        reached_[seed] = 1;
        bool open = false;
        while (!frontier_.empty()) {
            const std::uint32_t t = frontier_.back();
            frontier_.pop_back();
            component.push_back(t);
            for (int k = 0; k < 3; ++k) open = !sharedEdge(t, corner(t, k), corner(t, (k + 1) % 3)) || open;
        }
        return open;
    }

  private:
    std::uint32_t corner(std::uint32_t t, int k) const { return welded_[mesh_.triangles[t][k]]; }
    bool hasCorner(std::uint32_t t, std::uint32_t v) const {
        return corner(t, 0) == v || corner(t, 1) == v || corner(t, 2) == v;
    }
    // Whether edge (a, b) of t belongs to another triangle; those not reached yet join the frontier.
    bool sharedEdge(std::uint32_t t, std::uint32_t a, std::uint32_t b) {
        bool shared = false;
        for (std::size_t i = around_.first[a]; i < around_.first[a + 1]; ++i) {
            const std::uint32_t u = around_.ids[i];
            if (u == t || !hasCorner(u, b)) continue;
            shared = true;
            if (!reached_[u]) reached_[u] = 1, frontier_.push_back(u);
        }
        return shared;
    }

    const TriangleMesh &mesh_;
    std::vector<std::uint32_t> welded_;
    TrianglesAround around_;
    std::vector<char> reached_;
    std::vector<std::uint32_t> frontier_;
};

}  // namespace

std::vector<char> inClosedSurface(const TriangleMesh &mesh) {
    const std::size_t n = mesh.triangleCount();
    std::vector<char> closed(n, 0);
    if (n == 0) return closed;
    ComponentWalk components(mesh);
    std::vector<std::uint32_t> component;
    for (std::uint32_t seed = 0; seed < n; ++seed) {
        if (components.reached(seed) || components.walk(seed, component)) continue;
        for (std::uint32_t t : component) closed[t] = 1;
    }
    return closed;
}

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
    ComponentWalk components(mesh);
    std::vector<std::uint32_t> component;
    for (std::size_t seed = firstDown; seed < n; ++seed) {
        if (!down[seed] || components.reached(std::uint32_t(seed))) continue;
        const bool open = components.walk(std::uint32_t(seed), component);
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
