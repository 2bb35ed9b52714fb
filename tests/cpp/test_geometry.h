#pragma once

// Small meshes for tests: planes, boxes, spheres, built through makeTriangleMesh like real input.
#include <cmath>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"

namespace firn::test {

inline TriangleMesh meshOf(const std::vector<glm::vec3> &points, const std::vector<unsigned> &indices) {
    std::vector<float> flat;
    for (const glm::vec3 &p : points) flat.insert(flat.end(), {p.x, p.y, p.z});
    return makeTriangleMesh(flat.data(), points.size(), indices.data(), indices.size() / 3);
}

// A square of side `size` m centred at `centre`, tilted `slope` rad about the x axis, facing up.
inline TriangleMesh plane(float size, glm::vec3 centre = {0, 0, 0}, float slope = 0.0f) {
    const float h = 0.5f * size, c = std::cos(slope), s = std::sin(slope);
    auto at = [&](float x, float y) { return centre + glm::vec3(x, y * c, y * s); };
    return meshOf({at(-h, -h), at(h, -h), at(h, h), at(-h, h)}, {0, 1, 2, 0, 2, 3});
}

// An axis-aligned box from lo to hi, faces outward.
inline TriangleMesh box(glm::vec3 lo, glm::vec3 hi) {
    std::vector<glm::vec3> p;
    for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    return meshOf(p, {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                      2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5});
}

// A UV sphere, faces outward.
inline TriangleMesh sphere(glm::vec3 centre, float radius, int rings = 32, int segments = 64) {
    const float pi = 3.14159265f;
    std::vector<glm::vec3> p;
    std::vector<unsigned> t;
    for (int i = 0; i <= rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const float theta = pi * i / rings, phi = 2 * pi * j / segments;
            p.push_back(centre + radius * glm::vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                                                    std::cos(theta)));
        }
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const unsigned a = i * segments + j, b = i * segments + (j + 1) % segments;
            const unsigned c = a + segments, d = b + segments;
            t.insert(t.end(), {a, c, b, b, c, d});
        }
    return meshOf(p, t);
}

}  // namespace firn::test
