#include "firn/geometry/orientation.h"

#include <gtest/gtest.h>

#include "test_geometry.h"

namespace firn {

namespace {

const glm::vec3 kUp(0, 0, 1);

TriangleMesh reversed(TriangleMesh mesh) {
    for (glm::uvec3 &t : mesh.triangles) std::swap(t[1], t[2]);
    return mesh;
}

// Every triangle with its own three vertices, as some importers write them.
TriangleMesh unwelded(const TriangleMesh &mesh) {
    TriangleMesh out;
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
        const auto base = static_cast<unsigned>(out.positions.size());
        for (int k = 0; k < 3; ++k) out.positions.push_back(mesh.vertex(t, k));
        out.triangles.emplace_back(base, base + 1, base + 2);
    }
    return out;
}

std::size_t facingUp(const TriangleMesh &mesh) {
    std::size_t n = 0;
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) n += mesh.crossNormal(t).z > 0.0f;
    return n;
}

}  // namespace

TEST(OrientOpenSurfaces, TurnsAFlippedPlaneUp) {
    TriangleMesh mesh = reversed(test::plane(2.0f));
    ASSERT_EQ(facingUp(mesh), 0u);
    const Reorientation changed = orientOpenSurfaces(mesh, kUp);
    EXPECT_EQ(changed.surfaces, 1u);
    EXPECT_EQ(changed.triangles, 2u);
    EXPECT_EQ(facingUp(mesh), 2u);
}

TEST(OrientOpenSurfaces, LeavesAnUpwardPlaneAlone) {
    TriangleMesh mesh = test::plane(2.0f);
    const Reorientation changed = orientOpenSurfaces(mesh, kUp);
    EXPECT_EQ(changed.surfaces, 0u);
    EXPECT_EQ(changed.triangles, 0u);
}

TEST(OrientOpenSurfaces, TurnsTowardsUpNotWorldZ) {
    // Wind: "up" is against the snowfall; a plane facing +z is turned when up is -z.
    TriangleMesh mesh = test::plane(2.0f);
    EXPECT_EQ(orientOpenSurfaces(mesh, -kUp).triangles, 2u);
}

TEST(OrientOpenSurfaces, LeavesClosedBoxesAloneWhateverTheirNormals) {
    // A box has two downward triangles (its bottom) outward, two downward (its top) inverted: both untouched.
    for (const TriangleMesh &box : {test::box({0, 0, 0}, {1, 1, 1}), reversed(test::box({0, 0, 0}, {1, 1, 1}))}) {
        TriangleMesh mesh = box;
        const Reorientation changed = orientOpenSurfaces(mesh, kUp);
        EXPECT_EQ(changed.triangles, 0u);
        EXPECT_EQ(mesh.triangles, box.triangles);
    }
}

TEST(OrientOpenSurfaces, WeldsSplitVerticesBeforeDecidingOpenOrClosed) {
    // An inverted box whose faces share no vertex index is still closed; a split flipped plane is still open.
    TriangleMesh box = unwelded(reversed(test::box({0, 0, 0}, {1, 1, 1})));
    EXPECT_EQ(orientOpenSurfaces(box, kUp).triangles, 0u);
    TriangleMesh sheet = unwelded(reversed(test::plane(1.0f)));
    const Reorientation changed = orientOpenSurfaces(sheet, kUp);
    EXPECT_EQ(changed.surfaces, 1u);
    EXPECT_EQ(changed.triangles, 2u);
}

TEST(OrientOpenSurfaces, TurnsOnlyTheDownwardTrianglesOfAnOpenSurfaceWoundBothWays) {
    // A unit square split along its diagonal, one half wound up and one down (an inconsistent import), beside
    // a plane facing up everywhere: one open surface, one triangle turned.
    TriangleMesh square;
    square.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    square.triangles = {{0, 1, 2}, {0, 3, 2}};
    TriangleMesh mesh = merge({square, test::plane(1.0f, {0, 5, 0})});
    const Reorientation changed = orientOpenSurfaces(mesh, kUp);
    EXPECT_EQ(changed.surfaces, 1u);
    EXPECT_EQ(changed.triangles, 1u);
    EXPECT_EQ(facingUp(mesh), 4u);
}

TEST(OrientOpenSurfaces, TurnsOnlyTheOpenPartsOfAMixedSoup) {
    const TriangleMesh outward = test::box({0, 0, 0}, {1, 1, 1});
    const TriangleMesh inverted = reversed(test::box({3, 0, 0}, {4, 1, 1}));
    TriangleMesh mesh = merge({outward, inverted, reversed(test::plane(1.0f, {0, 5, 0})),
                               test::plane(1.0f, {0, 8, 0}), reversed(test::plane(1.0f, {0, 11, 0}))});
    const Reorientation changed = orientOpenSurfaces(mesh, kUp);
    EXPECT_EQ(changed.surfaces, 2u);   // the two flipped planes
    EXPECT_EQ(changed.triangles, 4u);
    EXPECT_EQ(facingUp(mesh), 2u + 2u + 6u);  // each box's top (outward) or bottom (inverted), and three planes
}

// Boxes have an inside whatever their winding, and unwelded; planes have none whatever theirs (the Monte Carlo skips
// gathering points only inside closed surfaces: a ground wound downwards must not enclose the snow above it).
TEST(InClosedSurface, NamesTheTrianglesOfClosedComponentsWhateverTheirWinding) {
    const TriangleMesh mesh = merge({test::box({0, 0, 0}, {1, 1, 1}), reversed(test::box({3, 0, 0}, {4, 1, 1})),
                                     unwelded(test::box({6, 0, 0}, {7, 1, 1})),  // 3 x 12 triangles
                                     reversed(test::plane(1.0f, {0, 5, 0})), test::plane(1.0f, {0, 8, 0})});
    const std::vector<char> closed = inClosedSurface(mesh);
    ASSERT_EQ(closed.size(), mesh.triangleCount());
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) EXPECT_EQ(closed[t] != 0, t < 36) << "triangle " << t;
}

// The search (on a const mesh) names the triangles the orientation turns, and applying them gives its mesh: the
// shelter is built from the targets while it runs beside (shelterTargets).
TEST(OrientOpenSurfaces, FindingTheTurnsLeavesTheMeshAndNamesWhatOrientingTurns) {
    const TriangleMesh soup = merge({reversed(test::box({3, 0, 0}, {4, 1, 1})), reversed(test::plane(1.0f, {0, 5, 0})),
                                     test::plane(1.0f, {0, 8, 0})});
    const OpenSurfaceTurns turns = findOpenSurfaceTurns(soup, kUp);
    EXPECT_EQ(turns.changed.surfaces, 1u);
    EXPECT_EQ(turns.changed.triangles, turns.triangles.size());
    TriangleMesh oriented = soup;
    const Reorientation changed = orientOpenSurfaces(oriented, kUp);
    EXPECT_EQ(changed.triangles, turns.changed.triangles);
    TriangleMesh applied = soup;
    applyTurns(applied, turns);
    EXPECT_EQ(applied.triangles, oriented.triangles);
    EXPECT_NE(soup.triangles, oriented.triangles);  // something turned: the comparison above says something
}

}  // namespace firn
