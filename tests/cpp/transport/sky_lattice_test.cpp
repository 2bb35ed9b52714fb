// The sky traced on a coarse lattice of surface voxels and taken from it where it varies slowly (onSkyLattice,
// skyDonorsAgree, fillFromSkyDonors: incident_light.h). A flat slab half under a black roof: the oracle is the
// view factor of the open sky past the roof's straight edge.
#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/color.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.01;                   // m
constexpr int kLength = 48, kWidth = 24;          // voxels along x (across the roof's edge) and y
constexpr double kEdge = 23.7, kRoof = 4.6;       // voxels: the roof's edge (x) and height (z)
constexpr double kRayStart = 4.0;                 // voxels: a top patch's patchOutside (its centre at 3, + 1)

// The share of a horizontal patch's cosine-weighted sky that an opaque half-plane at height H over x < kEdge leaves
// open, at d = x - kEdge: the half-plane's edge seen from the patch is a great circle tilted by beta (tan beta =
// d / H) from the vertical, projected onto the base disc a half-ellipse of area (pi / 2) sin beta (Nusselt's analogue).
double openShare(double x) {
    const double d = x - kEdge, H = kRoof - kRayStart;
    return 0.5 * (1.0 + d / std::hypot(d, H));
}

Scene roofedSlab() {
    auto grid = test::densityGrid(kVoxel);
    grid->fill(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(kLength - 1, kWidth - 1, 3)), 300.0f);
    Scene scene;
    scene.medium = std::make_shared<Medium>(grid, VolumeOptics{16.4, Rgb(0.999), 0.85});  // 98 optical depths a voxel
    scene.sky.radiance = Rgb(1.0);
    const float x = float(kEdge * kVoxel), z = float(kRoof * kVoxel);
    const float v[] = {-1, -1, z, x, -1, z, x, 1, z, -1, 1, z};
    const unsigned t[] = {0, 1, 2, 0, 2, 3};
    scene.occluders = std::make_shared<Occluders>(makeTriangleMesh(v, 4, t, 2), std::vector<Rgb>(2, Rgb(0.0)));
    return scene;
}

}  // namespace

// The top's voxels off the lattice whose donors agree take their mean: far from the edge (open sky, or deep under the
// roof) most of them, and their sky (pooled over neighbours, as FINAL's) matches the view factor within the traced
// rays' noise. At the roof's edge, a voxel between donors on either side of it (one in the roof's shadow, one in the
// open, 0.03 against 0.72 of the sky) traces its own rays.
TEST(SkyLattice, TakesTheSkyFromAgreeingDonorsAndTracesAtTheRoofsEdge) {
    const Scene scene = roofedSlab();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    // The lattice goes with the sky pooled over neighbours (FINAL, DRAFT); without it (REFERENCE) all traced.
    const IncidentLight light = computeIncidentLight(scene, topo, {9, 1, 7, true}, SubProgress(nullptr, 0.0, 1.0));
    EXPECT_EQ(computeIncidentLight(scene, topo, {9, 1, 7, false}, SubProgress(nullptr, 0.0, 1.0)).skyTraced,
              topo.surfaceVoxels());
    int farPatches = 0, farTraced = 0, edgePatches = 0, edgeFilled = 0, filled = 0;
    double error = 0.0, squares = 0.0;  // sky share minus the view factor, over the filled top voxels
    for (std::size_t i = 0; i < topo.size(); ++i) {
        const openvdb::Coord c = topo.coord[i];
        if (!topo.patches[i].isSurface() || topo.patches[i].normal.z < 0.99 || c.x() < 2 || c.x() > kLength - 3 ||
            c.y() < 2 || c.y() > kWidth - 3)
            continue;
        const bool fromDonors = light.fromDonors[i] != 0;
        if (std::abs(c.x() - kEdge) > 6.0) ++farPatches, farTraced += !fromDonors;
        if (c.x() == 23) ++edgePatches, edgeFilled += fromDonors;
        if (!fromDonors) continue;
        const double e = channelMean(glm::dvec3(light.skyOnSurface[i])) / kPi - openShare(double(c.x()));
        error += e, squares += e * e, ++filled;
    }
    ASSERT_GT(farPatches, 400);
    EXPECT_LT(double(farTraced) / farPatches, 0.4);  // a quarter is the lattice
    ASSERT_EQ(edgePatches, kWidth - 4);
    EXPECT_EQ(edgeFilled, 0);
    ASSERT_GT(filled, 400);
    const double mean = error / filled, spread = std::sqrt(squares / filled - mean * mean);
    EXPECT_LT(std::abs(mean), 3.0 * spread / std::sqrt(double(filled)) + 0.005) << "spread " << spread;
    EXPECT_LT(spread, 0.08);  // a 9-ray estimate's own at half the sky open: sqrt(0.25 / 9) = 0.17
}

}  // namespace firn
