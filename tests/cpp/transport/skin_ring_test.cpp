// The sun a convex surface's soft skin intercepts beyond the patches' sphere (skin_ring.h, skinRingGrowth), against
// the chord geometry done independently: a ray passing a sphere of radius R at distance b from its centre crosses the
// skin's density (radial profile sigma(r)) with optical depth tau(b) = 2 integral sigma(r) r dr / sqrt(r^2 - b^2), here
// taken with r = b cosh t, and the skin stops pi ((R + delta)^2 - R^2) = integral 2 pi b (1 - exp(-tau(b))) db of sun.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <memory>

#include <gtest/gtest.h>

#include "box_scene.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/skin_ring.h"
#include "firn/transport/snow_topology.h"

namespace firn {

namespace {

// A 12 x 12 x 6 block of snow (rho0 kg/m^3, sigma_t h per full voxel `depthPerVoxel`) with one layer of `skin` times
// rho0 on top: along z the trilinear density falls linearly from the top full voxel's centre (1) through the skin
// layer's (skin) to 0 a voxel further.
Scene skinnedBlock(double depthPerVoxel, float skin) {
    initializeOpenVdb();
    constexpr float rho0 = 300.0f;
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setTransform(openvdb::math::Transform::createLinearTransform(test::kBoxVoxel));
    grid->fill(openvdb::CoordBBox({0, 0, 0}, {11, 11, 5}), rho0);
    if (skin > 0.0f) grid->fill(openvdb::CoordBBox({0, 0, 6}, {11, 11, 6}), skin * rho0);
    Scene scene;
    scene.medium = std::make_shared<Medium>(
        grid, VolumeOptics{depthPerVoxel / (test::kBoxVoxel * rho0), Rgb(0.999), 0.85});
    scene.suns = {SunLight{glm::dvec3(0.0, 0.0, 1.0), Rgb(1.0), 0.0093}};
    return scene;
}

// The top's centre surface patch (normal +z) and the height (voxels) of its patch surface above the full layer's
// centres, z = 5.
std::size_t topCentre(const SnowTopology &topo, const openvdb::Coord &at) {
    for (std::size_t i = 0; i < topo.size(); ++i)
        if (topo.coord[i] == at) return i;
    return topo.size();
}

// (1 + kappa delta)^2 by the chord integral above, the skin's optical depth per voxel depth(y) at height y (voxels)
// above the sphere of radius R = 1 / kappa, zero from `top` on.
double chordGrowth(double kappa, const std::function<double(double)> &depth, double top) {
    const double R = 1.0 / kappa;
    constexpr int kB = 4000, kT = 4000;
    double ring = 0.0;
    for (int m = 0; m < kB; ++m) {
        const double b = R + (m + 0.5) * top / kB;
        const double tMax = std::acosh((R + top) / b);
        double tau = 0.0;
        for (int k = 0; k < kT; ++k) {
            const double r = b * std::cosh((k + 0.5) * tMax / kT);
            tau += 2.0 * depth(r - R) * r * tMax / kT;  // dr / sqrt(r^2 - b^2) = dt; r dt from the r factor
        }
        ring += 2.0 * b * (1.0 - std::exp(-tau)) * top / kB;
    }
    return 1.0 + ring / (R * R);
}

// The block's top-centre patch (above voxel (6, 6, 5)) and its topology.
struct TopPatch {
    explicit TopPatch(const Scene &scene)
        : topo(buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0))),
          i(topCentre(topo, openvdb::Coord(6, 6, 5))) {}
    // Found, its normal straight up (+z).
    bool facesUp() const { return i < topo.size() && std::abs(topo.patches[i].normal.z - 1.0) < 1e-9; }
    // Voxels from its node out to its surface (surfaceOffset).
    double offset(const Medium &medium, Medium::Accessor &density) const {
        return bake::surfaceOffset(medium, topo.coord[i], topo.patches[i].normal, density);
    }
    SnowTopology topo;
    std::size_t i;
};

}  // namespace

// An opaque skin stops every ray that touches it: the ring is its whole thickness. With no skin layer the top full
// voxel's density falls linearly to 0 a voxel above its node, through half at half a voxel (surfaceOffset), so
// delta = 1/2 voxel, at kappa 0.1 a growth of 1.05^2.
TEST(SkinRing, AnOpaqueSkinInterceptsItsWholeThickness) {
    const Scene scene = skinnedBlock(1e5, 0.0f);
    const TopPatch top(scene);
    ASSERT_TRUE(top.facesUp());
    Medium::Accessor density = scene.medium->accessor();
    const double offset = top.offset(*scene.medium, density);
    const SnowTopology &topo = top.topo;
    const std::size_t i = top.i;
    EXPECT_NEAR(offset, 0.5, 1e-6);
    EXPECT_NEAR(bake::skinRingGrowth(*scene.medium, topo, i, 0.1, offset, density), 1.05 * 1.05, 2e-3);
    EXPECT_NEAR(bake::skinRingGrowth(*scene.medium, topo, i, 0.02, offset, density), 1.01 * 1.01, 1e-3);
}

// A skin of finite optical depth: the ramp from the full voxel's centre through a skin layer of 0.3 rho0 to nothing,
// sigma_t h 4 per full voxel, against the chord integral over its exact piecewise-linear profile. The surface: the
// density 1 - 0.7 z (z voxels above the node) falls to half at z = 5/7.
TEST(SkinRing, ASoftSkinInterceptsWhatItsChordsStop) {
    const Scene scene = skinnedBlock(4.0, 0.3f);
    const TopPatch top(scene);
    ASSERT_TRUE(top.facesUp());
    Medium::Accessor density = scene.medium->accessor();
    const double offset = top.offset(*scene.medium, density);
    const SnowTopology &topo = top.topo;
    const std::size_t i = top.i;
    EXPECT_NEAR(offset, 5.0 / 7.0, 1e-3);
    // Heights y above the surface, z = y + 5/7: the skin layer's centre at z 1, nothing from z 2.
    const auto depth = [](double y) {
        const double z = y + 5.0 / 7.0;
        if (z < 1.0) return 4.0 * (1.0 - 0.7 * z);
        return z < 2.0 ? 4.0 * 0.3 * (2.0 - z) : 0.0;
    };
    for (const double kappa : {0.15, 0.05}) {
        const double expected = chordGrowth(kappa, depth, 2.0 - 5.0 / 7.0);
        EXPECT_GT(expected - 1.0, 0.1 * kappa);  // a real ring, not the empty case
        EXPECT_NEAR(bake::skinRingGrowth(*scene.medium, topo, i, kappa, offset, density) - 1.0, expected - 1.0,
                    0.02 * (expected - 1.0))
            << kappa;
    }
}

// The suite's ball (bench/bake_suite.py, ball: fill clip(1/2 - (r - R) / h, 0, 1), R 8 voxels) has its half level on
// the sphere of radius R: each surface patch's surface lies R - |node - centre| voxels out of its node, up to the
// trilinear blend's bend where the fill clips (under 0.1 voxel) and the patch normal's tilt off the radius.
TEST(SkinRing, ABallsSurfaceLiesOnItsHalfLevel) {
    constexpr double R = 8.0, centre = 12.0;  // voxels, index space
    auto grid = test::densityGrid(test::kBoxVoxel);
    auto acc = grid->getAccessor();
    for (int x = 0; x <= 24; ++x)
        for (int y = 0; y <= 24; ++y)
            for (int z = 0; z <= 24; ++z) {
                const double r = std::sqrt((x - centre) * (x - centre) + (y - centre) * (y - centre) +
                                           (z - centre) * (z - centre));
                const double fill = std::clamp(0.5 - (r - R), 0.0, 1.0);
                if (fill > 0.0) acc.setValue(openvdb::Coord(x, y, z), float(300.0 * fill));
            }
    Scene scene;
    scene.medium = std::make_shared<Medium>(grid, VolumeOptics{20.0 / (test::kBoxVoxel * 300.0), Rgb(0.999), 0.85});
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    Medium::Accessor density = scene.medium->accessor();
    double sum = 0.0, worst = 0.0;
    int count = 0;
    for (std::size_t i = 0; i < topo.size(); ++i) {
        if (!topo.patches[i].isSurface()) continue;
        const openvdb::Coord c = topo.coord[i];
        const double r = std::sqrt((c.x() - centre) * (c.x() - centre) + (c.y() - centre) * (c.y() - centre) +
                                   (c.z() - centre) * (c.z() - centre));
        const double miss = bake::surfaceOffset(*scene.medium, topo.coord[i], topo.patches[i].normal, density) - (R - r);
        sum += miss, worst = std::max(worst, std::abs(miss)), ++count;
    }
    ASSERT_GT(count, 500);
    EXPECT_NEAR(sum / count, 0.0, 0.05);
    EXPECT_LT(worst, 0.2);
}

}  // namespace firn
