#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"

namespace firn {

// What orientOpenSurfaces changed.
struct Reorientation {
    std::size_t surfaces = 0;   // open components with at least one triangle turned
    std::size_t triangles = 0;  // triangles whose winding was reversed
};

// Snow falls on the upper side of a sheet whatever its normals say, but only a closed surface has an inside.
// Splits the mesh into edge-connected components (vertices welded by exact position, so unwelded imports still
// connect); a component with a boundary edge (an edge of one triangle) is open, and its triangles facing away
// from `up` are reversed to face it. Closed components keep their winding: their normals say where the inside is.
Reorientation orientOpenSurfaces(TriangleMesh &mesh, const glm::vec3 &up);

// The triangles orientOpenSurfaces would reverse (ascending), and what that changes; the mesh untouched, so the
// search can run beside readers of it and a copy is made only when something turns.
struct OpenSurfaceTurns {
    Reorientation changed;
    std::vector<std::uint32_t> triangles;
};
OpenSurfaceTurns findOpenSurfaceTurns(const TriangleMesh &mesh, const glm::vec3 &up);

// Per triangle, whether its edge-connected component (welded as orientOpenSurfaces welds) is closed: no edge of
// one triangle. Only a closed surface has an inside.
std::vector<char> inClosedSurface(const TriangleMesh &mesh);

// Reverses the winding of the triangles `turns` names.
void applyTurns(TriangleMesh &mesh, const OpenSurfaceTurns &turns);

}  // namespace firn
