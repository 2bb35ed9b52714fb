// Which voxels the bake traces rather than diffuses (bake_thin_snow.h, thinVoxels): a scene holding both thin
// voxels and a traced layer, whose TracedSnow::inLayer must line up with thin then wholePieces, the order the bake
// light traces them whole in (bakeScattering), so that the layer's faces, not the thin voxels', gather their own
// source (addFaceSources).
#include <algorithm>

#include <gtest/gtest.h>

#include "box_scene.h"
#include "firn/transport/bake_thin_snow.h"
#include "firn/transport/snow_topology.h"

namespace firn {

// The suite's slab_thin (24 x 24 x 3 voxels of sigma_t h 2, omega 0.99, g 0.6: a traced layer, its sigma_tr h 0.81
// summed cubed 925, over kMaxTracedPieceReducedVolume) and, apart from it, a lump of 2 x 2 x 2 voxels of sigma_t h 1
// (a small piece: thin).
TEST(ThinSnow, ATracedLayersFlagsLineUpWithThinThenWholePieces) {
    const VolumeOptics optics{10.0, Rgb(0.99), 0.6};
    const float perTau = float(1.0 / (optics.extinctionPerDensity * test::kBoxVoxel));  // density of sigma_t h 1
    Scene scene = test::boxScene(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(23, 23, 2)), 2.0f * perTau,
                                 optics, glm::dvec3(0.866, 0.0, 0.5));
    auto grid = scene.medium->density().deepCopy();
    grid->fill(openvdb::CoordBBox(openvdb::Coord(40, 40, 10), openvdb::Coord(41, 41, 11)), perTau);
    scene.medium = std::make_shared<Medium>(grid, optics);
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    const bake::TracedSnow snow = bake::thinVoxels(*scene.medium, topo);
    ASSERT_EQ(snow.thin.size(), 8u);
    ASSERT_EQ(snow.wholePieces.size(), 24u * 24u * 3u);
    ASSERT_EQ(snow.inLayer.size(), snow.thin.size() + snow.wholePieces.size());
    EXPECT_TRUE(std::none_of(snow.inLayer.begin(), snow.inLayer.begin() + 8, [](bool b) { return b; }));
    EXPECT_TRUE(std::all_of(snow.inLayer.begin() + 8, snow.inLayer.end(), [](bool b) { return b; }));
}

}  // namespace firn
