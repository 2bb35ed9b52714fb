#pragma once

#include <glm/vec3.hpp>

namespace firn {

// Whether triangle abc and the closed axis-aligned box [lo, hi] share a point: the separating axis test (the box's
// three axes, the triangle's normal, the nine edge cross products; Akenine-Moeller, "Fast 3D triangle-box overlap
// testing", 2001), in double precision. Both are closed sets: a triangle that only touches the box (at a point of a
// face, an edge or a corner, up to the rounding) overlaps it. A collinear triangle is the segment it spans (its zero
// normal separates nothing; the box's axes and their cross products with the segment decide).
bool triangleOverlapsBox(const glm::dvec3 &lo, const glm::dvec3 &hi, const glm::dvec3 &a, const glm::dvec3 &b,
                         const glm::dvec3 &c);

}  // namespace firn
