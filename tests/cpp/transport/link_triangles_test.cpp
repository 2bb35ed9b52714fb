// LinkTriangles (link_triangles.h): the pre-test never drops a link whose occluderOnLink ray hits, and spares the links
// away from every triangle. The oracle is Embree's own ray (occluderOnLink) on every link of a block of voxels.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/geometry/mesh.h"
#include "firn/transport/link_triangles.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.01;  // m; voxel (i, j, k)'s centre lies at (i, j, k) voxels

Medium oneVoxel() {
    auto grid = test::densityGrid(kVoxel);
    grid->getAccessor().setValue(openvdb::Coord(0), 100.0f);
    return Medium(grid, VolumeOptics{1.0, Rgb(0.9), 0.6});
}

Occluders triangle(const glm::dvec3 &a, const glm::dvec3 &b, const glm::dvec3 &c) {  // voxels
    std::vector<float> v;
    for (const glm::dvec3 &p : {a, b, c})
        for (int k = 0; k < 3; ++k) v.push_back(float(p[k] * kVoxel));
    const unsigned t[] = {0, 1, 2};
    return Occluders(makeTriangleMesh(v.data(), 3, t, 1), std::vector<Rgb>(1, Rgb(0.5)));
}

struct Links {
    int hits = 0, kept = 0, all = 0;
    bool dropped = false;  // a hit the pre-test skipped
};

// Every link up each axis from the voxels of [-3, 3]^3, each asked of the pre-test and of Embree.
Links testEveryLink(const Medium &medium, const Occluders &occluders) {
    const openvdb::CoordBBox lowers(openvdb::Coord(-3), openvdb::Coord(3));
    const LinkTriangles near(medium, occluders, lowers, linkPad(medium, occluders));
    Links links;
    for (auto c = lowers.beginXYZ(); c; ++c)
        for (int axis = 0; axis < 3; ++axis) {
            const bool hit = occluderOnLink(medium, occluders, *c, axis).has_value();
            const bool kept = near.mayCross(*c, axis);
            links.hits += hit, links.kept += kept, ++links.all;
            links.dropped |= hit && !kept;
        }
    return links;
}

}  // namespace

TEST(LinkTriangles, KeepEveryHitOfTrianglesMadeToGrazeTheLinks) {
    const Medium medium = oneVoxel();
    const double n = kLinkRayNudge;
    struct Case {
        const char *what;
        glm::dvec3 a, b, c;
    };
    const std::vector<Case> cases{
        {"a sliver across the x link near voxel (0,0,0)'s corner", {0.5, -1e-6, -2}, {0.5, 1e-6, -2}, {0.5, 0, 2}},
        {"a vertex on the x link's segment", {0.5, 0, 0}, {0.5, 1, 1}, {0.5, 1, -1}},
        {"an edge touching the x link from above", {0.5, -1, 0}, {0.5, 1, 0}, {0.5, 0, 1}},
        {"a plane through the voxels' centres", {-9, -9, 0}, {9, -9, 0}, {0, 9, 0}},
        {"a plane just past the z links' nudged start", {-9, -9, 1.01 * n}, {9, -9, 1.01 * n}, {0, 9, 1.01 * n}},
        {"a plane at the z links' far end", {-9, -9, 1.0 + n}, {9, -9, 1.0 + n}, {0, 9, 1.0 + n}},
        {"a thin wall on the y links at the centres' x", {0, -9, -9}, {1e-7, 9, -9}, {0, 0, 9}},
        {"a sliver along the z link, crossing no other", {1e-5, 1e-5, 0.2}, {-1e-5, 1e-5, 0.8}, {1e-5, -1e-5, 0.5}},
    };
    for (const Case &c : cases) {
        const Links links = testEveryLink(medium, triangle(c.a, c.b, c.c));
        EXPECT_FALSE(links.dropped) << c.what;
        EXPECT_GT(links.hits, 0) << c.what << ": the case grazes no link";
    }
}

TEST(LinkTriangles, KeepEveryHitOfRandomTrianglesOnTheVoxelLattice) {
    // Vertices on voxel centres, links' ends and halfway points, each jittered by 0 or up to 1e-6 voxels: the
    // triangles graze the links' ends and lie in or along them.
    const Medium medium = oneVoxel();
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> halves(-6, 6);
    std::uniform_real_distribution<double> jitter(-1e-6, 1e-6);
    std::bernoulli_distribution jittered(0.5);
    int hits = 0, kept = 0, all = 0;
    for (int t = 0; t < 300; ++t) {
        glm::dvec3 v[3];
        for (auto &p : v)
            for (int k = 0; k < 3; ++k) p[k] = 0.5 * halves(rng) + (jittered(rng) ? jitter(rng) : 0.0);
        const Links links = testEveryLink(medium, triangle(v[0], v[1], v[2]));
        EXPECT_FALSE(links.dropped) << "triangle " << t;
        hits += links.hits, kept += links.kept, all += links.all;
    }
    EXPECT_GT(hits, 1000);     // the triangles cross links
    EXPECT_LT(kept, all / 2);  // and the pre-test spares most links away from them
}

TEST(LinkTriangles, SpareEveryLinkAVoxelAwayFromTheTriangles) {
    const Medium medium = oneVoxel();
    // A plane at z = 4.5 voxels: no link of the block reaches past z = 4 + kLinkRayNudge.
    const Links links = testEveryLink(medium, triangle({-9, -9, 4.5}, {9, -9, 4.5}, {0, 9, 4.5}));
    EXPECT_EQ(links.kept, 0);
    // At z = 3.5 the z links from the top layer cross it and only they (49 of them) are kept.
    const Links top = testEveryLink(medium, triangle({-9, -9, 3.5}, {9, -9, 3.5}, {0, 9, 3.5}));
    EXPECT_EQ(top.hits, 49);
    EXPECT_EQ(top.kept, 49);
}

}  // namespace firn
