#pragma once

#include <glm/vec3.hpp>

namespace firn {

// Whether triangle abc and the closed axis-aligned box [lo, hi] share a point: the separating axis test (the box's
// three axes, the triangle's normal, the nine edge cross products; Akenine-Moeller, "Fast 3D triangle-box overlap
// testing", 2001), in double precision. A triangle touching a face of the box overlaps it.
bool triangleOverlapsBox(const glm::dvec3 &lo, const glm::dvec3 &hi, const glm::dvec3 &a, const glm::dvec3 &b,
                         const glm::dvec3 &c);

}  // namespace firn
