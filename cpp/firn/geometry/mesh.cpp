#include "firn/geometry/mesh.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include "firn/util/error.h"

namespace firn {

glm::vec3 TriangleMesh::crossNormal(std::size_t t) const {
    const glm::vec3 a = vertex(t, 0), b = vertex(t, 1), c = vertex(t, 2);
    return glm::cross(b - a, c - a);
}

double TriangleMesh::area(std::size_t t) const { return 0.5 * glm::length(crossNormal(t)); }

TriangleMesh makeTriangleMesh(const float *positions, std::size_t vertexCount, const unsigned *indices,
                              std::size_t triangleCount) {
    TriangleMesh mesh;
    mesh.positions.resize(vertexCount);
    float extent = 0.0f;  // m, largest |coordinate|
    for (std::size_t i = 0; i < vertexCount; ++i) {
        const glm::vec3 p(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw InvalidArgument("vertex " + std::to_string(i) + " has a non-finite coordinate (NaN or inf)");
        mesh.positions[i] = p;
        extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    }
    // Area below (1e-6 of the extent)^2 is rounding noise, not a surface.
    const double minArea = std::pow(1e-6 * std::max(extent, 1e-3f), 2.0);
    mesh.triangles.reserve(triangleCount);
    for (std::size_t t = 0; t < triangleCount; ++t) {
        const glm::uvec3 tri(indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]);
        for (int k = 0; k < 3; ++k)
            if (tri[k] >= vertexCount)
                throw InvalidArgument("triangle " + std::to_string(t) + " refers to vertex " +
                                      std::to_string(tri[k]) + " of " + std::to_string(vertexCount));
        mesh.triangles.push_back(tri);
        if (mesh.area(mesh.triangles.size() - 1) <= minArea) {
            mesh.triangles.pop_back();
            ++mesh.droppedDegenerate;
        }
    }
    return mesh;
}

TriangleMesh merge(const std::vector<TriangleMesh> &meshes) {
    TriangleMesh out;
    for (const TriangleMesh &m : meshes) {
        const auto offset = static_cast<unsigned>(out.positions.size());
        out.positions.insert(out.positions.end(), m.positions.begin(), m.positions.end());
        for (const glm::uvec3 &t : m.triangles) out.triangles.push_back(t + offset);
        out.droppedDegenerate += m.droppedDegenerate;
    }
    return out;
}

}  // namespace firn
