#include "firn/geometry/mesh.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "firn/util/error.h"

namespace firn {

TEST(TriangleMesh, KeepsValidTrianglesAndComputesArea) {
    const float p[] = {0, 0, 0, 2, 0, 0, 0, 3, 0};
    const unsigned t[] = {0, 1, 2};
    const TriangleMesh mesh = makeTriangleMesh(p, 3, t, 1);
    ASSERT_EQ(mesh.triangleCount(), 1u);
    EXPECT_DOUBLE_EQ(mesh.area(0), 3.0);  // right triangle, legs 2 m and 3 m
    EXPECT_GT(mesh.crossNormal(0).z, 0.0f);  // counter-clockwise seen from +z
}

TEST(TriangleMesh, DropsDegenerateTriangles) {
    const float p[] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0};
    const unsigned t[] = {0, 1, 2, 0, 1, 3, 1, 1, 3};  // collinear, valid, repeated vertex
    const TriangleMesh mesh = makeTriangleMesh(p, 4, t, 3);
    EXPECT_EQ(mesh.triangleCount(), 1u);
    EXPECT_EQ(mesh.droppedDegenerate, 2u);
}

TEST(TriangleMesh, RejectsNonFiniteVertices) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const unsigned t[] = {0, 1, 2};
    const float withNan[] = {0, 0, 0, 1, nan, 0, 0, 1, 0};
    const float withInf[] = {0, 0, inf, 1, 0, 0, 0, 1, 0};
    EXPECT_THROW(makeTriangleMesh(withNan, 3, t, 1), InvalidArgument);
    EXPECT_THROW(makeTriangleMesh(withInf, 3, t, 1), InvalidArgument);
}

TEST(TriangleMesh, RejectsOutOfRangeIndices) {
    const float p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const unsigned t[] = {0, 1, 3};
    EXPECT_THROW(makeTriangleMesh(p, 3, t, 1), InvalidArgument);
}

TEST(TriangleMesh, MergeOffsetsIndices) {
    const float p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const unsigned t[] = {0, 1, 2};
    const TriangleMesh a = makeTriangleMesh(p, 3, t, 1);
    const TriangleMesh merged = merge({a, a});
    ASSERT_EQ(merged.triangleCount(), 2u);
    EXPECT_EQ(merged.triangles[1], glm::uvec3(3, 4, 5));
}

}  // namespace firn
