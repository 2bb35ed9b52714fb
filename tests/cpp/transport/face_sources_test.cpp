// The face sources of a floating layer's traced voxels (bake_traced_voxels.h, addFaceSources): up to
// kMaxTracedSteps of paths, so Esc must stop them.
#include <gtest/gtest.h>

#include "box_scene.h"
#include "firn/transport/bake_traced_voxels.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/error.h"

namespace firn {

namespace {

// A layer one voxel thick, 4 x 4 voxels of sigma_t h 15 with air above and below, under a sun.
Scene floatingLayer() {
    return test::boxScene(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(3, 3, 0)), 150.0f,  // 1500 / m
                          VolumeOptics{10.0, Rgb(0.999), 0.7}, glm::dvec3(0.866, 0.0, 0.5));
}

}  // namespace

// Every voxel holds a source for each of its two air faces; cancelled, the faces' paths stop (Cancelled).
TEST(FaceSources, EachTwoSidedVoxelHoldsItsFacesAndEscStopsThem) {
    const Scene scene = floatingLayer();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    std::vector<openvdb::Coord> voxels;
    for (int x = 0; x < 4; ++x)
        for (int y = 0; y < 4; ++y) voxels.emplace_back(x, y, 0);
    const SubProgress none(nullptr, 0.0, 1.0);
    const bake::GatheringPlan plan{64, 64.0 * 1000.0 * double(voxels.size())};
    bake::MonteCarloVoxels traced = bake::traceSources(scene, voxels, plan.paths, 3, none);
    bake::addFaceSources(scene, topo, voxels, plan, 5, none, traced);
    ASSERT_EQ(traced.faces.size(), voxels.size());
    for (const bake::FaceSources &faces : traced.faces) EXPECT_EQ(faces.open, 0b110000u);  // -z and +z

    Progress cancelled;
    cancelled.cancel();
    bake::MonteCarloVoxels again = bake::traceSources(scene, voxels, plan.paths, 3, none);
    EXPECT_THROW(bake::addFaceSources(scene, topo, voxels, plan, 5, SubProgress(&cancelled, 0.0, 1.0), again),
                 Cancelled);
}

}  // namespace firn
