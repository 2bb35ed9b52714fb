// Which voxels the bake traces rather than diffuses (bake_thin_snow.h, thinVoxels): a scene holding both thin
// voxels and a traced layer, whose TracedSnow::inLayer must line up with thin then wholePieces, the order the bake
// light traces them whole in (bakeScattering), so that the layer's faces, not the thin voxels', gather their own
// source (addFaceSources); a lump apart from a dense layer; and which traced voxels the renderer scatters
// (scatteredVoxels).
#include <algorithm>

#include <gtest/gtest.h>

#include "box_scene.h"
#include "firn/geometry/mesh.h"
#include "firn/transport/bake_thin_snow.h"
#include "firn/transport/snow_topology.h"

namespace firn {

namespace {

// The voxels `box` of `scene`'s snow filled with `density` too.
void addBox(Scene &scene, const openvdb::CoordBBox &box, float density) {
    auto grid = scene.medium->density().deepCopy();
    grid->fill(box, density);
    scene.medium = std::make_shared<Medium>(grid, scene.medium->optics());
}

// The density of sigma_t h 1 under `optics` on the box scene's voxels (kg/m^3).
float densityOfOneOpticalDepth(const VolumeOptics &optics) {
    return float(1.0 / (optics.extinctionPerDensity * test::kBoxVoxel));
}

// A block of 10 x 10 x 6 voxels of sigma_t h 3 under the sun 30 degrees up.
Scene blockScene(const VolumeOptics &optics) {
    return test::boxScene(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(9, 9, 5)),
                          3.0f * densityOfOneOpticalDepth(optics), optics, glm::dvec3(0.866, 0.0, 0.5));
}

// What `scene`'s snow traces (thinVoxels), asserted to be `lump`'s 2 x 2 x 2 voxels alone, thin (none traced whole).
bake::TracedSnow tracedLumpAlone(const Scene &scene, const openvdb::CoordBBox &lump) {
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    bake::TracedSnow snow = bake::thinVoxels(*scene.medium, topo);
    EXPECT_TRUE(snow.wholePieces.empty());
    EXPECT_EQ(snow.thin.size(), 8u);
    EXPECT_TRUE(
        std::all_of(snow.thin.begin(), snow.thin.end(), [&](const openvdb::Coord &c) { return lump.isInside(c); }));
    return snow;
}

}  // namespace

// The suite's slab_thin (24 x 24 x 3 voxels of sigma_t h 2, omega 0.99, g 0.6: a traced layer, its sigma_tr h 0.81
// summed cubed 925, over kMaxTracedPieceReducedVolume) and, apart from it, a lump of 2 x 2 x 2 voxels of sigma_t h 1
// (a small piece: thin).
TEST(ThinSnow, ATracedLayersFlagsLineUpWithThinThenWholePieces) {
    const VolumeOptics optics{10.0, Rgb(0.99), 0.6};
    const float perTau = densityOfOneOpticalDepth(optics);
    Scene scene = test::boxScene(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(23, 23, 2)), 2.0f * perTau,
                                 optics, glm::dvec3(0.866, 0.0, 0.5));
    addBox(scene, openvdb::CoordBBox(openvdb::Coord(40, 40, 10), openvdb::Coord(41, 41, 11)), perTau);
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    const bake::TracedSnow snow = bake::thinVoxels(*scene.medium, topo);
    ASSERT_EQ(snow.thin.size(), 8u);
    ASSERT_EQ(snow.wholePieces.size(), 24u * 24u * 3u);
    ASSERT_EQ(snow.inLayer.size(), snow.thin.size() + snow.wholePieces.size());
    EXPECT_TRUE(std::none_of(snow.inLayer.begin(), snow.inLayer.begin() + 8, [](bool b) { return b; }));
    EXPECT_TRUE(std::all_of(snow.inLayer.begin() + 8, snow.inLayer.end(), [](bool b) { return b; }));
}

// A small piece is a dense layer, left to the diffusion, only where it is shaped as one: on a grey ground, a dusting of
// 6 x 6 x 1 voxels and, apart from it, a lump of 2 x 2 x 2 (both sigma_t h 15, omega 0.999, g 0.7: bumpy_plate's snow,
// sigma_tr h 4.5, no voxel deeper than 2.25 in it, each with snow or the ground on one side of each axis). The dusting
// stays a layer (diffused, neither traced nor thin: snow_on_ground_bench.py --one-voxel); the lump is traced (it was a
// "layer" before: spray_dense's lumps read +103 % diffused, docs/benchmarks.md spray-budget).
TEST(ThinSnow, ALumpIsTracedWhereADustingIsADenseLayer) {
    const VolumeOptics optics{10.0, Rgb(0.999), 0.7};
    const float perTau = densityOfOneOpticalDepth(optics);
    Scene scene = test::boxScene(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(5, 5, 0)), 15.0f * perTau,
                                 optics, glm::dvec3(0.866, 0.0, 0.5));
    const openvdb::CoordBBox lump(openvdb::Coord(20, 20, 0), openvdb::Coord(21, 21, 1));
    addBox(scene, lump, 15.0f * perTau);
    const float z = float(-0.25 * test::kBoxVoxel);  // a quarter voxel under the lowest voxels' centres
    const float v[] = {-1, -1, z, 1, -1, z, 1, 1, z, -1, 1, z};
    const unsigned t[] = {0, 1, 2, 0, 2, 3};
    scene.occluders = std::make_shared<Occluders>(makeTriangleMesh(v, 4, t, 2), std::vector<Rgb>(2, Rgb(0.5)));
    tracedLumpAlone(scene, lump);
}

// A block of 10 x 10 x 6 voxels of sigma_t h 3 under a fringe of 10 x 10 x 1 of sigma_t h 1 (g 0.6: its sigma_tr h
// 1.38 at omega 0.9, 1.20 at 0.999, under kThickReducedDepth, so the fringe is traced; the block has an inside and is
// diffused) and, apart, a lump of 2 x 2 x 2 of sigma_t h 1 (a small piece, traced). Where the snow absorbs (omega 0.9)
// the renderer leaves the diffused block's fringe to its traced values (a 5 cm ball of such snow read +10 % bias with
// it scattered: docs/benchmarks.md, lead-88) and scatters the lump; where it scatters (omega 0.999) it scatters both.
TEST(ThinSnow, TheRendererLeavesADiffusedBodysTracedFringeAloneWhereTheSnowAbsorbs) {
    const openvdb::CoordBBox fringe(openvdb::Coord(0, 0, 6), openvdb::Coord(9, 9, 6)),
        lump(openvdb::Coord(30, 30, 0), openvdb::Coord(31, 31, 1));
    for (const double omega : {0.9, 0.999}) {
        const VolumeOptics optics{10.0, Rgb(omega), 0.6};
        const float perTau = densityOfOneOpticalDepth(optics);
        Scene scene = blockScene(optics);
        addBox(scene, fringe, perTau);
        addBox(scene, lump, perTau);
        const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
        const bake::TracedSnow snow = bake::thinVoxels(*scene.medium, topo);
        ASSERT_TRUE(snow.wholePieces.empty()) << omega;
        ASSERT_EQ(snow.thin.size(), 100u + 8u) << omega;
        const std::vector<openvdb::Coord> scattered = bake::scatteredVoxels(*scene.medium, snow);
        const auto inFringe = [&](const openvdb::Coord &c) { return fringe.isInside(c); };
        EXPECT_EQ(std::count_if(scattered.begin(), scattered.end(), inFringe), omega < 0.95 ? 0 : 100) << omega;
        EXPECT_EQ(std::count_if(scattered.begin(), scattered.end(), [&](const openvdb::Coord &c) {
                      return lump.isInside(c); }), 8) << omega;
    }
}

// The block above under a layer of 10 x 10 x 1 voxels of sigma_t h 1e-9 (next to no snow: the float rounding of an
// antialiased fill left 2.3e-15 of the snow's density over a flat top, which was traced as thin snow and scattered by
// the renderer, the mixed render +27 %; docs/benchmarks.md, lead-93 6.) and a lump of 2 x 2 x 2 voxels of it apart:
// neither is snow to trace, while the lump of sigma_t h 1 beside it still is.
TEST(ThinSnow, NextToNoDensityIsNoSnowToTrace) {
    const VolumeOptics optics{10.0, Rgb(0.999), 0.6};
    const float perTau = densityOfOneOpticalDepth(optics);
    Scene scene = blockScene(optics);
    addBox(scene, openvdb::CoordBBox(openvdb::Coord(0, 0, 6), openvdb::Coord(9, 9, 6)), 1e-9f * perTau);
    addBox(scene, openvdb::CoordBBox(openvdb::Coord(20, 20, 0), openvdb::Coord(21, 21, 1)), 1e-9f * perTau);
    const openvdb::CoordBBox lump(openvdb::Coord(30, 30, 0), openvdb::Coord(31, 31, 1));
    addBox(scene, lump, perTau);
    EXPECT_EQ(bake::scatteredVoxels(*scene.medium, tracedLumpAlone(scene, lump)).size(), 8u);
}

// A lump of 2 x 2 x 2 voxels of sigma_t h 1 in absorbing snow (omega 0.9, where the renderer leaves a diffused body's
// traced fringe alone) wrapped in a voxel of sigma_t h 1e-9 all round: that wrap is no diffused snow beside it, so the
// renderer still scatters the lump (the wrap counted as snow, it left it to its traced values).
TEST(ThinSnow, NextToNoDensityIsNoDiffusedSnowBesideATracedLump) {
    const VolumeOptics optics{10.0, Rgb(0.9), 0.6};
    const float perTau = densityOfOneOpticalDepth(optics);
    Scene scene = blockScene(optics);
    addBox(scene, openvdb::CoordBBox(openvdb::Coord(29, 29, 1), openvdb::Coord(32, 32, 4)), 1e-9f * perTau);
    const openvdb::CoordBBox lump(openvdb::Coord(30, 30, 2), openvdb::Coord(31, 31, 3));
    addBox(scene, lump, perTau);
    EXPECT_EQ(bake::scatteredVoxels(*scene.medium, tracedLumpAlone(scene, lump)).size(), 8u);
}

}  // namespace firn
