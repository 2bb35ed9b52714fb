#include "firn/geometry/box_triangle.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/geometric.hpp>

namespace firn {

namespace {

// Whether the triangle's vertices (about the box's centre) and the box of half-size `half` project apart on `axis`.
bool apartOn(const glm::dvec3 &axis, const std::array<glm::dvec3, 3> &v, const glm::dvec3 &half) {
    const double p0 = glm::dot(axis, v[0]), p1 = glm::dot(axis, v[1]), p2 = glm::dot(axis, v[2]);
    const double r = half.x * std::abs(axis.x) + half.y * std::abs(axis.y) + half.z * std::abs(axis.z);
    return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
}

}  // namespace

bool triangleOverlapsBox(const glm::dvec3 &lo, const glm::dvec3 &hi, const glm::dvec3 &a, const glm::dvec3 &b,
                         const glm::dvec3 &c) {
    const glm::dvec3 centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    const std::array<glm::dvec3, 3> v{a - centre, b - centre, c - centre};
    for (int k = 0; k < 3; ++k) {  // the box's faces: the triangle's bounding box against the box
        glm::dvec3 axis(0.0);
        axis[k] = 1.0;
        if (apartOn(axis, v, half)) return false;
    }
    const std::array<glm::dvec3, 3> edges{v[1] - v[0], v[2] - v[1], v[0] - v[2]};
    if (apartOn(glm::cross(edges[0], edges[1]), v, half)) return false;  // the triangle's plane
    for (const glm::dvec3 &e : edges)
        for (int k = 0; k < 3; ++k) {
            glm::dvec3 axis(0.0);
            axis[k] = 1.0;
            if (apartOn(glm::cross(axis, e), v, half)) return false;
        }
    return true;
}

}  // namespace firn
