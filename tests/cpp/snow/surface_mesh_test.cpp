#include "firn/snow/surface_mesh.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>
#include <openvdb/tools/LevelSetSphere.h>

#include "firn/util/error.h"
#include "firn/util/openvdb_library.h"

namespace firn {

namespace {

const SubProgress kNoProgress(nullptr, 0.0, 1.0);
constexpr double kPi = 3.14159265358979323846;

// A sphere of radius r (m) at c as a narrow-band level set of voxel h (OpenVDB's own construction).
openvdb::FloatGrid::Ptr sphere(float r, openvdb::Vec3f c, float h) {
    initializeOpenVdb();
    return openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(r, c, h, 3.0f);
}

// Signed volume enclosed by the triangles (divergence theorem: sum of det(a, b, c) / 6): positive when every
// triangle winds counter-clockwise seen from outside.
double enclosedVolume(const SurfaceMesh &m) {
    double v = 0.0;
    for (const openvdb::Vec3I &t : m.triangles) {
        const openvdb::Vec3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
        v += a.dot(b.cross(c)) / 6.0;
    }
    return v;
}

}  // namespace

TEST(SurfaceMesh, LiesOnTheZeroCrossingAndFacesOut) {
    const float r = 0.5f, h = 0.02f;
    const openvdb::Vec3f c(1.0f, -2.0f, 0.25f);
    const SurfaceMesh m = meshSurface(*sphere(r, c, h), {}, kNoProgress);
    ASSERT_GT(m.triangles.size(), 1000u);
    for (const openvdb::Vec3s &p : m.vertices) EXPECT_NEAR((p - c).length(), r, h);  // within a voxel of |x - c| = r
    // Enclosed volume 4/3 pi r^3; the inscribed polygons lose O(h^2 / r) of it.
    EXPECT_NEAR(enclosedVolume(m), 4.0 / 3.0 * kPi * r * r * r, 0.02 * 4.0 / 3.0 * kPi * r * r * r);
    EXPECT_EQ(m.adaptivity, 0.0);
    EXPECT_DOUBLE_EQ(m.voxelSize, h);
}

TEST(SurfaceMesh, MeetsTheTriangleBudget) {
    const float r = 0.5f, h = 0.01f;
    const openvdb::Vec3f c(0.0f);
    const openvdb::FloatGrid::Ptr grid = sphere(r, c, h);
    const std::size_t full = meshSurface(*grid, {}, kNoProgress).triangles.size();
    for (const std::size_t budget : {full / 3, full / 20, std::size_t(2000)}) {
        const SurfaceMesh m = meshSurface(*grid, {0.0, budget}, kNoProgress);
        EXPECT_LE(m.triangles.size(), budget);
        EXPECT_GT(m.triangles.size(), budget / 20);  // decimated, not wiped out
        // Still the sphere, within a voxel of the level set it was made from (coarser when rebuilt).
        for (const openvdb::Vec3s &p : m.vertices) EXPECT_NEAR((p - c).length(), r, m.voxelSize);
        EXPECT_NEAR(enclosedVolume(m), 4.0 / 3.0 * kPi * r * r * r, 0.1 * 4.0 / 3.0 * kPi * r * r * r);
    }
}

// The budget's search counts triangles (one quad per edge crossing the isovalue) and meshes once: a budget of
// exactly the full mesh's triangles keeps it, one less makes it coarser.
TEST(SurfaceMesh, CountsTheTrianglesItWouldMake) {
    const openvdb::FloatGrid::Ptr grid = sphere(0.5f, openvdb::Vec3f(0.1f, 0.0f, -0.2f), 0.01f);
    for (const double isovalue : {0.0, 0.0075}) {
        const SurfaceMesh full = meshSurface(*grid, {0.0, 0, isovalue}, kNoProgress);
        const SurfaceMesh kept = meshSurface(*grid, {0.0, full.triangles.size(), isovalue}, kNoProgress);
        EXPECT_EQ(kept.voxelSize, full.voxelSize);
        EXPECT_EQ(kept.triangles, full.triangles);
        EXPECT_EQ(kept.vertices, full.vertices);
        const SurfaceMesh coarser = meshSurface(*grid, {0.0, full.triangles.size() - 1, isovalue}, kNoProgress);
        EXPECT_GT(coarser.voxelSize, full.voxelSize);
        // At twice the voxel size too: a budget the search reaches from the full mesh in one step (a quarter of
        // it or more) and that holds the coarser mesh ends there, with the triangles counted.
        EXPECT_DOUBLE_EQ(coarser.voxelSize, 2.0 * full.voxelSize);
        const std::size_t budget = std::max(coarser.triangles.size(), (full.triangles.size() + 3) / 4);
        const SurfaceMesh again = meshSurface(*grid, {0.0, budget, isovalue}, kNoProgress);
        EXPECT_EQ(again.voxelSize, coarser.voxelSize);
        EXPECT_EQ(again.triangles, coarser.triangles);
    }
}

TEST(SurfaceMesh, BadInputIsRefused) {
    const openvdb::FloatGrid::Ptr grid = sphere(0.5f, openvdb::Vec3f(0.0f), 0.05f);
    EXPECT_THROW(meshSurface(*grid, {1.5, 0}, kNoProgress), InvalidArgument);
    EXPECT_THROW(meshSurface(*grid, {0.0, 10}, kNoProgress), InvalidArgument);
    openvdb::FloatGrid fog;
    fog.setGridClass(openvdb::GRID_FOG_VOLUME);
    EXPECT_THROW(meshSurface(fog, {}, kNoProgress), InvalidArgument);
    openvdb::FloatGrid empty;
    empty.setGridClass(openvdb::GRID_LEVEL_SET);
    EXPECT_TRUE(meshSurface(empty, {}, kNoProgress).triangles.empty());
}

TEST(SurfaceMesh, StopsWhenCancelled) {
    const openvdb::FloatGrid::Ptr grid = sphere(0.5f, openvdb::Vec3f(0.0f), 0.01f);
    Progress progress;
    progress.cancel();
    EXPECT_THROW(meshSurface(*grid, {0.0, 200}, SubProgress(&progress, 0.0, 1.0)), Cancelled);
}

}  // namespace firn
