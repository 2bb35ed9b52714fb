// The points drawn where cameras see a thick voxel (visible_points.h): their draws are work the bake's budget
// counts (SourceEstimate::steps, bake_traced_voxels.cpp planGathering).
#include "firn/transport/visible_points.h"

#include <cstdio>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "box_scene.h"
#include "firn/transport/traced_source.h"

namespace firn {

namespace {

// A lump of 8^3 voxels, sigma_t h = 10 (as spray_dense's lumps: thick, g 0.85), under a sun and sky.
Scene lumpScene() {
    Scene scene = test::boxScene(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(7)), 100.0f,  // 1000 / m
                                 VolumeOptics{10.0, Rgb(0.99), 0.85}, glm::dvec3(0.5, 0.3, 0.8));
    scene.sky.radiance = Rgb(0.1);
    return scene;
}

}  // namespace

// The draws read the density at least once per candidate and direction (the optical depth ahead).
TEST(VisiblePoints, CountTheirDensityLookups) {
    const Scene scene = lumpScene();
    const MonteCarloReference reference(scene);
    const openvdb::Coord voxel(4, 4, 7);  // on the lump's sunlit top
    constexpr int kSamples = 16;
    Rng rng(3, 0), u(5, 0);
    long steps = 0;
    const std::vector<glm::dvec3> points = visiblePoints(*scene.medium, voxel, reference.directions(), kSamples, [&] {
        return std::array<double, 3>{u.uniform(), u.uniform(), u.uniform()};
    }, rng, steps);
    ASSERT_EQ(points.size(), std::size_t(kSamples));
    EXPECT_GE(steps, long(kSamples) * kVisibleCandidates * kSourceDirections);
}

// Gathered where cameras see it, a thick voxel's estimate counts the points' draws besides its paths: per path
// it costs more than gathered over the voxel (on spray_dense the draws cost about as much as the paths).
TEST(VisiblePoints, TheirWorkCountsInTheEstimatesSteps) {
    const Scene scene = lumpScene();
    const MonteCarloReference reference(scene);
    const openvdb::Coord voxel(4, 4, 7);
    Medium::Accessor density = scene.medium->accessor();
    ASSERT_TRUE(gatheredWhereSeen(*scene.medium, density, voxel));
    constexpr int kSamples = 64;
    const long over = reference.sourceIn(voxel, kSamples, 9, 0, Gathering::Spread).steps;
    const long seen = reference.sourceIn(voxel, kSamples, 9, 0, Gathering::WhereSeen).steps;
    std::printf("steps per path: over the voxel %.0f, where seen %.0f\n", double(over) / kSamples, double(seen) / kSamples);
    EXPECT_GT(seen, over);
}

}  // namespace firn
