// Where a surface patch's gather and sky rays start (patchOutside, incident_light.h): out of its own snow, never
// inside other snow. A narrow V-groove (bench/groove_probe.py's): a wall's patch near the floor's line looks along
// its normal across the groove at the opposite wall, whose density ramp it meets a few voxels out
// (docs/benchmarks.md, valley-answer 1 and gather-start). Where a sun's beam starts (patchOutsideAlong): in front of
// the snow that shades the patch (docs/benchmarks.md, bumpy-sides).
#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"

namespace firn {

namespace {

constexpr int kWidth = 24, kLength = 12, kHeight = 20;  // voxels of 1 cm
constexpr double kVoxel = 0.01;                         // m
constexpr double kFloor = 4.0;                          // voxels: the floor's line above the grid's z = 0
const double kMiddle = (kWidth - 1) / 2.0 + 0.23;       // the floor line's x (voxels), off the grid's nodes
const double kAngle = 55.0 * M_PI / 180.0;              // the walls' slope

// Signed distances (voxels) above the wall rising towards -x and the one rising towards +x, at index point q.
double aboveLeft(const glm::dvec3 &q) { return (q.z - kFloor) * std::cos(kAngle) + (q.x - kMiddle) * std::sin(kAngle); }
double aboveRight(const glm::dvec3 &q) { return (q.z - kFloor) * std::cos(kAngle) - (q.x - kMiddle) * std::sin(kAngle); }

// A wall's fill (0-1) at index point q, antialiased along its normal over a voxel, as the grid's voxels hold it and
// read trilinearly between them (Medium::densityAt); `above` is the wall's signed distance.
double wallFill(double (*above)(const glm::dvec3 &), const glm::dvec3 &q) {
    const glm::dvec3 base = glm::floor(q), t = q - base;
    double fill = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 bit((corner >> 0) & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        const glm::dvec3 weight = glm::mix(1.0 - t, t, bit);
        fill += weight.x * weight.y * weight.z * std::clamp(0.5 - above(base + bit), 0.0, 1.0);
    }
    return fill;
}

// The snow under both walls, each antialiased along its own normal over a voxel, sigma_t h 15.
Medium vGroove() {
    auto grid = test::densityGrid(kVoxel);
    auto acc = grid->getAccessor();
    for (int x = 0; x < kWidth; ++x)
        for (int y = 0; y < kLength; ++y)
            for (int z = 1; z < kHeight; ++z) {
                const glm::dvec3 q(x, y, z);
                const double fill = std::clamp(0.5 - std::min(aboveLeft(q), aboveRight(q)), 0.0, 1.0);
                if (fill > 0.0) acc.setValue(openvdb::Coord(x, y, z), float(100.0 * fill));
            }
    return Medium(grid, VolumeOptics{15.0, Rgb(0.999), 0.7});
}

}  // namespace

// Each wall's patches within 4 voxels of the floor's line, away from the grid's ends: the start lies outside the
// opposite wall's snow, its fill there under 2 % (an optical depth across a voxel under 0.3 of its 15). On main the
// patch next to the floor's line on the wall rising to -x started 4 voxels out, in 8 %.
TEST(PatchOutside, VGrooveWallPatchStartsOutsideTheOppositeWall) {
    const Medium medium = vGroove();
    const SnowTopology topo = buildSnowTopology(medium, Occluders{}, SubProgress(nullptr, 0.0, 1.0));
    Medium::Accessor density = medium.accessor();
    int patches = 0;
    double deepest = 0.0;  // the opposite wall's largest fill at a start
    for (std::size_t i = 0; i < topo.size(); ++i) {
        const openvdb::Coord &c = topo.coord[i];
        const double u = c.x() - kMiddle;
        const SurfacePatch &patch = topo.patches[i];
        if (!patch.isSurface() || patch.normal.z <= 0.0 || std::abs(u) > 4.0 || c.y() < 3 || c.y() > kLength - 4)
            continue;  // the grid's floor and ends
        const glm::dvec3 q = medium.worldToIndex(patchOutside(medium, topo, i, density));
        deepest = std::max(deepest, wallFill(u < 0.0 ? aboveRight : aboveLeft, q));
        ++patches;
    }
    EXPECT_GT(patches, 20);
    EXPECT_LT(deepest, 0.02);
}

// A tread three voxels deep at the foot of a wall eight high, both cut off at y 0 and the tread at x 0: the tread's
// corner voxel (air faces -x, -y, +z; a sharp corner) lies in the wall's shadow under a sun 30 degrees up from +x,
// its smooth normal (about (-1, -1, 1) / sqrt 3) 12 degrees past that sun's horizon. The beam's march must start in
// front of the wall: more than 5 optical depths of the trilinear snow between the start and the sun. On main it
// started 20 heights out along the light (the smooth normal's cosine floored at 0.05), past the wall, in none.
TEST(PatchOutside, SharpCornerInAWallsShadowStartsItsBeamInFrontOfTheWall) {
    auto grid = test::densityGrid(kVoxel);
    auto acc = grid->getAccessor();
    for (int x = 0; x < 12; ++x)
        for (int y = 0; y < 8; ++y)
            for (int z = 1; z < (x < 4 ? 4 : 12); ++z) acc.setValue(openvdb::Coord(x, y, z), 100.0f);
    const Medium medium(grid, VolumeOptics{15.0, Rgb(0.999), 0.7});  // sigma_t h 15
    const SnowTopology topo = buildSnowTopology(medium, Occluders{}, SubProgress(nullptr, 0.0, 1.0));
    Medium::Accessor density = medium.accessor();
    const glm::dvec3 w(std::cos(M_PI / 6.0), 0.0, std::sin(M_PI / 6.0));  // towards the sun
    std::size_t corner = topo.size();
    for (std::size_t i = 0; i < topo.size(); ++i)
        if (topo.coord[i] == openvdb::Coord(0, 0, 3)) corner = i;
    ASSERT_LT(corner, topo.size());
    ASSERT_TRUE(topo.patches[corner].sharp);
    ASSERT_LT(glm::dot(topo.patches[corner].normal, w), 0.0);
    ASSERT_TRUE(topo.patches[corner].facesTowards(w));
    const glm::dvec3 start = patchOutsideAlong(medium, topo, corner, w, density);
    double depth = 0.0;  // optical depth from the start towards the sun, 30 voxels, in 0.05-voxel steps
    for (int k = 0; k < 600; ++k)
        depth += 15.0 / 100.0 * medium.densityAt(start + (k + 0.5) * 0.05 * 0.01 * w, density) * 0.05;
    EXPECT_GT(depth, 5.0);
}

}  // namespace firn
