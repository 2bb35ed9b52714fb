// The snow's ceiling map against the trilinear density itself, read densely along the rays it proves empty.
#include "firn/transport/snow_ceiling.h"

#include <gtest/gtest.h>

#include "firn/transport/medium.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.02;  // m

// A block of snow: voxels x, y in 10 .. 19, z in 0 .. 4 (index space), 300 kg/m^3.
Medium blockOfSnow() {
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setTransform(openvdb::math::Transform::createLinearTransform(kVoxel));
    density->fill(openvdb::CoordBBox(openvdb::Coord(10, 10, 0), openvdb::Coord(19, 19, 4)), 300.0f, true);
    density->tree().voxelizeActiveTiles();
    return Medium(density, VolumeOptics{10.0, Rgb(0.99), 0.8});
}

// Whether the density is non-zero anywhere along the ray from `ijk` (index space) over 60 voxels, read every
// 1/64 voxel (the trilinear density, Medium::densityAt).
bool readsSnow(const Medium &medium, const glm::dvec3 &ijk, const glm::dvec3 &w) {
    Medium::Accessor read = medium.accessor();
    for (int k = 0; k <= 60 * 64; ++k)
        if (medium.densityAt(medium.indexToWorld(ijk + (k / 64.0) * w), read) > 0.0) return true;
    return false;
}

}  // namespace

// The trilinear density reaches one cell above the top voxels (z 4 .. 5) and one cell beyond the block towards -x
// and -y (a cell's corners are its own voxel and the next): a ray rising straight up is clear exactly from z = 5 over
// x, y in [9, 20).
TEST(SnowCeiling, ColumnsOverABlock) {
    const Medium medium = blockOfSnow();
    const SnowCeiling ceiling(medium.density());
    EXPECT_EQ(ceiling.ceiling(9, 9), 4);
    EXPECT_EQ(ceiling.ceiling(19, 19), 4);
    EXPECT_EQ(ceiling.ceiling(8, 15), SnowCeiling::kNone);
    EXPECT_EQ(ceiling.ceiling(20, 15), SnowCeiling::kNone);
    const glm::dvec3 up(0.0, 0.0, 1.0);
    for (const double x : {9.5, 15.0, 19.5}) {
        const glm::dvec3 below(x, 15.0, 4.9), above(x, 15.0, 5.1);
        EXPECT_TRUE(readsSnow(medium, below, up));
        EXPECT_FALSE(ceiling.clearAbove(below, up)) << x;
        EXPECT_FALSE(readsSnow(medium, above, up));
        EXPECT_TRUE(ceiling.clearAbove(above, up)) << x;
    }
}

// Over random rising rays around the block: every ray the map proves clear reads no snow (a map one cell too low,
// or not widened towards -x and -y, proves rays that graze the top), and the rays that pass over the block from
// above its top are proven.
TEST(SnowCeiling, ProvesOnlyRaysThatReadNoSnow) {
    const Medium medium = blockOfSnow();
    const SnowCeiling ceiling(medium.density());
    Rng rng(11, 0);
    int proven = 0, clearRays = 0;
    for (int r = 0; r < 2000; ++r) {
        const glm::dvec3 ijk(5.0 + 20.0 * rng.uniform(), 5.0 + 20.0 * rng.uniform(), 3.0 + 4.0 * rng.uniform());
        const glm::dvec3 w = sampleUniformCone(glm::dvec3(0.0, 0.0, 1.0), 0.02, rng.uniform(), rng.uniform());
        const bool snow = readsSnow(medium, ijk, w);
        const bool clear = ceiling.clearAbove(ijk, w);
        if (clear) {
            EXPECT_FALSE(snow) << ijk.x << " " << ijk.y << " " << ijk.z << " towards " << w.x << " " << w.y << " " << w.z;
        }
        proven += clear, clearRays += !snow;
    }
    // Rays that start above z = 5 are all proven; those below it that rise past the block's side are not always.
    EXPECT_GT(proven, clearRays / 2);
    EXPECT_LE(proven, clearRays);
}

}  // namespace firn
