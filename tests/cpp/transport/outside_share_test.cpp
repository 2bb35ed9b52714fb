// The share of a voxel's snow outside closed occluders (outside_share.h) against the volume a closed box leaves
// outside the voxel's cube, where the density is uniform over it (oracle: geometry).
#include "firn/transport/outside_share.h"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "box_scene.h"
#include "test_geometry.h"

namespace firn {

namespace {

// The voxel (1, 1, 1) of a 3^3 block of uniform snow (its cube z = 0.005 .. 0.015 m, the density uniform over it:
// its neighbours are snow), over a closed box whose top lies at `bottom` .. `top` (m) across the whole block.
Scene blockOverABox(float bottom, float top) {
    Scene scene = test::boxScene(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(2)), 100.0f,
                                 VolumeOptics{10.0, Rgb(0.99), 0.85}, glm::dvec3(0.0, 0.0, 1.0));
    const TriangleMesh box = test::box({-1.0f, -1.0f, bottom}, {1.0f, 1.0f, top});
    scene.occluders = std::make_shared<Occluders>(box, std::vector<Rgb>(box.triangleCount(), Rgb(0.5)));
    return scene;
}

struct ShareStats {
    double mean, rms;  // over the seeds; rms: of the difference from `exact`
};

ShareStats shares(const Scene &scene, double exact, int seeds) {
    const MonteCarloReference reference(scene);
    const PhotonTracer tracer(reference);
    Medium::Accessor density = scene.medium->accessor();
    double sum = 0.0, squares = 0.0;
    for (int s = 0; s < seeds; ++s) {
        Rng rng(17, std::uint64_t(s));
        const double share =
            outsideShare(*scene.medium, density, *scene.occluders, tracer, openvdb::Coord(1, 1, 1), rng);
        sum += share, squares += (share - exact) * (share - exact);
    }
    return ShareStats{sum / seeds, std::sqrt(squares / seeds)};
}

}  // namespace

// A closed box 0.37 voxel thick inside the voxel (a ski), between the planes of its centre and of points 0.45 voxel
// towards its corners: 0.63 of the voxel lies outside it. The 9 probes per voxel (before branch occluder-share)
// missed it: 1.
TEST(OutsideShare, CountsAClosedOccluderThinnerThanAVoxel) {
    const ShareStats s = shares(blockOverABox(0.0105f, 0.0142f), 0.63, 64);
    std::printf("share %.5f (exact 0.63), rms %.5f\n", s.mean, s.rms);
    EXPECT_NEAR(s.mean, 0.63, 0.005);
    EXPECT_LT(s.rms, 0.03);
}

// Faces on the planes of the voxel's cube and of its eighths cut none of them: each lies wholly on one side, exact.
TEST(OutsideShare, IsExactForFacesOnTheCubesPlanes) {
    EXPECT_EQ(shares(blockOverABox(-0.5f, 0.005f), 1.0, 1).mean, 1.0);          // the box under the cube's bottom
    EXPECT_NEAR(shares(blockOverABox(-0.5f, 0.01f), 0.5, 1).mean, 0.5, 1e-12);  // its top through the centre
    EXPECT_EQ(shares(blockOverABox(-0.5f, 0.015f), 0.0, 1).mean, 0.0);          // the cube wholly inside
}

// A voxel almost wholly inside (0.01 of it outside, over the box's top 0.49 voxel above its centre): its photon sums
// are divided by the share, so its relative error is the light's.
TEST(OutsideShare, OfAVoxelAlmostWhollyInside) {
    const ShareStats s = shares(blockOverABox(-0.5f, 0.0149f), 0.01, 256);
    std::printf("share %.5f (exact 0.01), rms %.5f (%.1f %%)\n", s.mean, s.rms, 100.0 * s.rms / 0.01);
    EXPECT_NEAR(s.mean, 0.01, 0.001);
}

}  // namespace firn
