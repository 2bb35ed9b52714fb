#include "firn/transport/block_masses.h"

#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/transport/incident_light.h"

namespace firn {
namespace {

constexpr double kVoxel = 0.01;  // m

openvdb::FloatGrid::Ptr boxOfSnow(const openvdb::CoordBBox &box, float density) {
    auto grid = test::densityGrid(kVoxel);
    grid->tree().fill(box, density, true);
    grid->tree().voxelizeActiveTiles();
    return grid;
}

TEST(BlockMasses, InAUniformCloudTheWindowedColumnIsTheRaysOwn) {
    // The kernel integrates to 1 across the ray: beside snow of one density everywhere within its reach, the
    // window sees the ray's own column rho (far - near), whatever the window's width and the ray's direction.
    const float rho = 200.0f;  // kg/m^3
    const auto grid = boxOfSnow(openvdb::CoordBBox(openvdb::Coord(-100), openvdb::Coord(99)), rho);
    const BlockMasses blocks(*grid, kVoxel, glm::dvec3(0.0));
    for (const glm::dvec3 &w : {glm::dvec3(0, 0, 1), glm::normalize(glm::dvec3(1, 2, 3))})
        for (double s : {0.05, 0.1, 0.2}) {
            const double near = 0.1, far = 0.2;
            EXPECT_NEAR(blocks.windowedColumn(glm::dvec3(0.0), w, near, far, s) / (rho * (far - near)), 1.0, 0.1)
                << "s " << s;
        }
}

TEST(BlockMasses, BesideALoneSmallPieceItTakesWhatTheConeSpreadsOverThePoint) {
    // A thin piece of radius r << s on the ray, the window spanning its block's depth: forwardShare's small-piece
    // limit r^2 / (2 s^2) of its column (the 2-D Cauchy kernel's mass within r), the window's own renormalisation
    // (out to 3 s) and the block's smoothing (s^2 / s'^2 = 0.87 here) aside. Off to the side beyond it: nothing.
    const float rho = 300.0f;
    const auto grid = boxOfSnow(openvdb::CoordBBox(openvdb::Coord(-2, -2, 48), openvdb::Coord(1, 1, 51)), rho);
    const BlockMasses blocks(*grid, kVoxel, glm::dvec3(0.0));
    const double column = rho * 4 * kVoxel, r = 2 * kVoxel * std::sqrt(4.0 / 3.14159265358979);  // the same area
    const double centre = 0.495, near = 0.43, far = 0.56, s = centre * forwardConeWidth(1e-9, 0.845);
    const double share = blocks.windowedColumn(glm::dvec3(-0.005, -0.005, 0.0), glm::dvec3(0, 0, 1), near, far, s) / column;
    const double renormalised = 1.0 / (1.0 - 1.0 / std::sqrt(10.0));
    EXPECT_NEAR(share / (forwardShare(r, centre, 1e-9, 0.845) * renormalised), 1.0, 0.25);
    EXPECT_GT(share, 0.0);
    EXPECT_EQ(blocks.windowedColumn(glm::dvec3(2.0, 0.0, 0.0), glm::dvec3(0, 0, 1), near, far, s), 0.0);
}

TEST(BlockMasses, SnowFarApartKeepsTheBlocksWithinBudget) {
    // Two voxels 200,000 apart (a fuzzed grid): 4^3 blocks over their box would be 2.5e9 floats (bad_alloc in a
    // bake); the finest blocks grow instead, and a window narrower than them counts nothing.
    auto grid = test::densityGrid(kVoxel);
    grid->tree().setValue(openvdb::Coord(-100000, -100000, 0), 300.0f);
    grid->tree().setValue(openvdb::Coord(100000, 100000, 0), 300.0f);
    const BlockMasses blocks(*grid, kVoxel, glm::dvec3(0.0));
    EXPECT_LE(blocks.storedBlocks(), std::size_t((1 << 22) * 8 / 7 + 64));
    EXPECT_EQ(blocks.windowedColumn(glm::dvec3(-1000.0, -1000.0, 0.0), glm::dvec3(0, 0, 1), 0.0, 0.01, 0.05), 0.0);
    const double wide = blocks.windowedColumn(glm::dvec3(-1000.0, -1000.0, -1.0), glm::dvec3(0, 0, 1), 0.0, 2.0, 2000.0);
    EXPECT_TRUE(std::isfinite(wide) && wide > 0.0);
}

}  // namespace
}  // namespace firn
