#include "firn/geometry/box_triangle.h"

#include <gtest/gtest.h>

namespace firn {

namespace {

// The unit cube [0, 1]^3: each case below was worked out by hand against it (the box's corner (1, 1, 1) has
// x + y = 2 and x + y + z = 3).
bool overlapsUnitCube(const glm::dvec3 &a, const glm::dvec3 &b, const glm::dvec3 &c) {
    return triangleOverlapsBox(glm::dvec3(0.0), glm::dvec3(1.0), a, b, c);
}

}  // namespace

// Horizontal at z = 0.5, its bounding box [0.3, 3]^2 over the cube's, its plane through the cube; the edge on the line
// x + y = 2.2 passes 0.2 beyond the cube's vertical edge x = y = 1 (x + y = 2 there), so only the axis z × that edge,
// (1, 1, 0), separates them. The same edge on x + y = 1.8 cuts the corner off the cube's section: (0.9, 0.9, 0.5).
TEST(BoxTriangle, SeparatedOnlyByAnEdgeCrossAxisAxis) {
    EXPECT_FALSE(overlapsUnitCube({1.9, 0.3, 0.5}, {0.3, 1.9, 0.5}, {3.0, 3.0, 0.5}));
    EXPECT_TRUE(overlapsUnitCube({1.5, 0.3, 0.5}, {0.3, 1.5, 0.5}, {3.0, 3.0, 0.5}));
}

// The triangle x + y + z = 3.3 in the positive octant, its bounding box [0, 3.3]^3 over the cube's: every edge axis
// overlaps (an edge x + y = 3.3 at z = 0 projects on (1, 1, 0) to [0, 3.3], the cube to [0, 2]), and only the plane,
// 0.3 beyond the corner (1, 1, 1), separates them. Its plane at 2.7 holds the cube's point (0.9, 0.9, 0.9).
TEST(BoxTriangle, SeparatedOnlyByItsPlane) {
    EXPECT_FALSE(overlapsUnitCube({3.3, 0.0, 0.0}, {0.0, 3.3, 0.0}, {0.0, 0.0, 3.3}));
    EXPECT_TRUE(overlapsUnitCube({2.7, 0.0, 0.0}, {0.0, 2.7, 0.0}, {0.0, 0.0, 2.7}));
}

// The box is closed: a triangle lying in its top face z = 1, or meeting it at its corner (1, 1, 1) alone, shares a
// point with it; lifted 1e-9 above it, none.
TEST(BoxTriangle, TouchingTheBoxOverlapsIt) {
    EXPECT_TRUE(overlapsUnitCube({0.25, 0.25, 1.0}, {0.75, 0.25, 1.0}, {0.25, 0.75, 1.0}));
    EXPECT_TRUE(overlapsUnitCube({1.0, 1.0, 1.0}, {2.0, 1.0, 1.0}, {1.0, 2.0, 1.0}));
    EXPECT_FALSE(overlapsUnitCube({0.25, 0.25, 1.0 + 1e-9}, {0.75, 0.25, 1.0 + 1e-9}, {0.25, 0.75, 1.0 + 1e-9}));
}

// Collinear triangles (a segment; their normal is zero and separates nothing): along the cube's diagonal from
// (-1, -1, -1) to (3, 3, 3), no vertex inside, it crosses the cube; on the line x + y = 2.2 at z = 0.5 (as above) it
// misses it, again separated by (1, 1, 0) alone.
TEST(BoxTriangle, CollinearTrianglesAreSegments) {
    EXPECT_TRUE(overlapsUnitCube({-1.0, -1.0, -1.0}, {2.0, 2.0, 2.0}, {3.0, 3.0, 3.0}));
    EXPECT_FALSE(overlapsUnitCube({1.9, 0.3, 0.5}, {0.3, 1.9, 0.5}, {1.1, 1.1, 0.5}));
}

}  // namespace firn
