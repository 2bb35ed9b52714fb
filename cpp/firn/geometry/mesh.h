#pragma once

#include <cstddef>
#include <initializer_list>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace firn {

// World-space triangles (m). Built only through makeTriangleMesh, so every mesh in the core is valid:
// finite vertices, indices in range, no degenerate triangles.
struct TriangleMesh {
    // m, world space. makeTriangleMesh and merge leave a spare vertex of capacity past the last one: Embree reads
    // 16 bytes there and then shares the array (RayCaster), without a copy.
    std::vector<glm::vec3> positions;
    std::vector<glm::uvec3> triangles;  // indices into positions
    std::size_t droppedDegenerate = 0;  // zero-area triangles removed while building

    std::size_t triangleCount() const { return triangles.size(); }
    bool empty() const { return triangles.empty(); }
    glm::vec3 vertex(std::size_t triangle, int corner) const { return positions[triangles[triangle][corner]]; }
    // Unnormalized geometric normal (length = 2 * area, m^2), counter-clockwise winding. Inline: passes over
    // a million triangles call it several times each.
    glm::vec3 crossNormal(std::size_t triangle) const {
        const glm::vec3 a = vertex(triangle, 0), b = vertex(triangle, 1), c = vertex(triangle, 2);
        return glm::cross(b - a, c - a);
    }
    double area(std::size_t triangle) const;  // m^2
};

// Validates and copies. Throws InvalidArgument for non-finite coordinates or out-of-range indices;
// drops (and counts) triangles whose area is below a relative epsilon of the mesh's extent.
TriangleMesh makeTriangleMesh(const float *positions, std::size_t vertexCount, const unsigned *indices,
                              std::size_t triangleCount);

// Joins meshes (targets of one snow layer, or every occluder) into one. By pointer: a list of meshes
// ({a, b}) would copy each first (a million triangles: 18 MB, serial).
TriangleMesh merge(std::initializer_list<const TriangleMesh *> meshes);
TriangleMesh merge(const std::vector<TriangleMesh> &meshes);

}  // namespace firn
