// The medium's ray walks against brute-force quadrature of the same trilinear density.
#include "firn/transport/medium.h"

#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>

#include "density_grid.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

// March skips the cells without snow, whole empty blocks at a time: along rays through scattered voxels (empty
// 2^3, 4^3 and 8^3 blocks between snowy cells) it must still integrate every snowy cell. Oracle: the midpoint
// rule on steps of 1/256 voxel along the whole ray, reading the density everywhere.
TEST(Medium, MarchIntegratesEverySnowyCell) {
    constexpr double kVoxel = 0.02;  // m
    auto density = test::densityGrid(kVoxel);
    Rng rng(7, 0);
    auto acc = density->getAccessor();
    for (int n = 0; n < 400; ++n)  // scattered snowy voxels in a 40^3 box: mostly air around them
        acc.setValue(openvdb::Coord(int(40 * rng.uniform()), int(40 * rng.uniform()), int(40 * rng.uniform())),
                     float(100.0 + 300.0 * rng.uniform()));
    const Medium medium(density, VolumeOptics{10.0, Rgb(0.99), 0.8});
    Medium::ColumnMarcher marcher(medium);
    Medium::Accessor read = medium.accessor();
    int snowyRays = 0;
    for (int r = 0; r < 300; ++r) {
        const glm::dvec3 origin = medium.indexToWorld(glm::dvec3(-5.0) + 50.0 * glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()));
        const glm::dvec3 w = sampleUniformCone(glm::dvec3(0.0, 0.0, 1.0), -1.0, rng.uniform(), rng.uniform());
        const double tMax = 60.0 * kVoxel;
        double marched = 0.0;  // kg/m^2
        marcher.march(origin, w, tMax, 1.0 / 16.0, [&](const openvdb::Vec3d &ijk, double dt) {
            marched += openvdb::tools::BoxSampler::sample(read, ijk) * dt;
            return true;
        });
        constexpr int kSteps = 60 * 256;
        double brute = 0.0;
        for (int i = 0; i < kSteps; ++i) brute += medium.densityAt(origin + (i + 0.5) * tMax / kSteps * w, read) * tMax / kSteps;
        // Tolerance: the midpoint rule's error at the kinks of the trilinear density (cell faces), about
        // rho h step^2 / 8 each, well below a skipped snowy cell's mass (of order rho h / 10).
        EXPECT_NEAR(marched, brute, 0.01 * 100.0 * kVoxel + 1e-2 * brute) << "ray " << r;
        snowyRays += brute > 0.0;
    }
    EXPECT_GT(snowyRays, 50);  // the rays do cross snow
}

// Tracking reads the density through DensitySampler, the last cell's eight values kept: it must read what
// Medium::densityAt (OpenVDB's BoxSampler, the one definition of the density) reads, bit for bit, whether a point
// lies in the last cell, a new one, or one read before, and whether its cell's corners lie in one leaf (read from
// it) or straddle leaves (the 12^3 snow spans two leaves per axis, and air beyond them). Oracle: Medium::densityAt
// itself.
TEST(Medium, DensitySamplerReadsAsDensityAtBitForBit) {
    constexpr double kVoxel = 0.02;  // m
    auto density = test::densityGrid(kVoxel);
    density->transform().postTranslate(openvdb::Vec3d(0.013, -0.4, 1.7));  // an origin off the voxel lattice
    Rng rng(11, 0);
    auto acc = density->getAccessor();
    for (int x = 0; x < 12; ++x)
        for (int y = 0; y < 12; ++y)
            for (int z = 0; z < 12; ++z)
                if (rng.uniform() < 0.6) acc.setValue(openvdb::Coord(x, y, z), float(300.0 * rng.uniform()));
    const Medium medium(density, VolumeOptics{10.0, Rgb(0.99), 0.8});
    Medium::DensitySampler sampler(medium);
    Medium::Accessor read = medium.accessor();
    int snowy = 0;
    for (int r = 0; r < 200; ++r) {
        glm::dvec3 p = medium.indexToWorld(glm::dvec3(-1.0) + 14.0 * glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()));
        const glm::dvec3 w = sampleUniformCone(glm::dvec3(0.0, 0.0, 1.0), -1.0, rng.uniform(), rng.uniform());
        for (int i = 0; i < 40; ++i) {  // steps of up to half a voxel, back and forth: cells kept, left and met again
            p += (i % 7 == 6 ? -2.0 : 1.0) * 0.5 * kVoxel * rng.uniform() * w;
            const double expected = medium.densityAt(p, read);
            EXPECT_EQ(sampler.at(medium.worldToIndex(p)), expected) << "ray " << r << " step " << i;
            snowy += expected > 0.0;
        }
    }
    EXPECT_GT(snowy, 2000);  // most points read snow
}

// Column steps over air a whole block of 8^3 to 64^3 cells at a time: rays from one lump of snow to another
// 150 voxels away, across empty 64^3 blocks, must still count both lumps. Oracle: the midpoint rule on steps of
// 1/64 voxel along the whole ray, reading the density everywhere.
TEST(Medium, ColumnCountsSnowAcrossEmptyBlocks) {
    constexpr double kVoxel = 0.02;  // m
    constexpr float kRho = 300.0f;   // kg/m^3
    auto density = test::densityGrid(kVoxel);
    auto acc = density->getAccessor();
    const openvdb::Coord lumps[2] = {openvdb::Coord(0, 0, 0), openvdb::Coord(150, 40, 90)};
    for (const openvdb::Coord &lump : lumps)
        for (int x = 0; x < 4; ++x)
            for (int y = 0; y < 4; ++y)
                for (int z = 0; z < 4; ++z) acc.setValue(lump.offsetBy(x, y, z), kRho);
    const Medium medium(density, VolumeOptics{10.0, Rgb(0.99), 0.8});
    Medium::ColumnMarcher marcher(medium);
    Medium::Accessor read = medium.accessor();
    Rng rng(11, 0);
    auto inLump = [&](const openvdb::Coord &lump) {
        return medium.indexToWorld(glm::dvec3(lump.x(), lump.y(), lump.z()) +
                                   glm::dvec3(0.5) + 2.0 * glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()));
    };
    for (int r = 0; r < 100; ++r) {
        const glm::dvec3 from = inLump(lumps[0]), to = inLump(lumps[1]);
        const glm::dvec3 w = glm::normalize(to - from);
        const double tMax = glm::length(to - from) + 10.0 * kVoxel;  // on through the far lump
        const double column = marcher.column(from, w, tMax, 1e30);
        const int steps = int(64.0 * tMax / kVoxel);
        double brute = 0.0;
        for (int i = 0; i < steps; ++i) brute += medium.densityAt(from + (i + 0.5) * tMax / steps * w, read) * tMax / steps;
        // Tolerance: the whole-voxel midpoint rule's error at the kinks of the trilinear density where the ray
        // enters and leaves each lump, about rho h / 8 each: far below a lump's own column (~ 2 rho h or more).
        EXPECT_NEAR(column, brute, 0.5 * kRho * kVoxel) << "ray " << r;
        EXPECT_GT(brute, 3.0 * kRho * kVoxel);  // the ray does cross both lumps' cores
    }
}

// A column's work in steps (columnSteps, what the bake's budget counts): inside snow, one per half-voxel step
// taken, up to tMax or the step that passes the limit. Oracle: the midpoint rule's step count, ceil(2 t / h).
TEST(Medium, ColumnCountsItsSteps) {
    constexpr double kVoxel = 0.02;  // m
    constexpr float kRho = 300.0f;   // kg/m^3
    auto density = test::densityGrid(kVoxel);
    density->fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(19)), kRho);
    const Medium medium(density, VolumeOptics{10.0, Rgb(0.99), 0.8});
    Medium::ColumnMarcher marcher(medium);
    const glm::dvec3 from = medium.indexToWorld(glm::dvec3(5.0, 9.5, 9.5)), x(1.0, 0.0, 0.0);
    EXPECT_EQ(marcher.columnSteps(), 0);
    marcher.column(from, x, 3.0 * kVoxel, 1e30);  // steps at 0.25, 0.75, ... 2.75 voxels
    EXPECT_EQ(marcher.columnSteps(), 6);
    marcher.column(from, x, 1e30, 2.2 * kRho * kVoxel);  // passes the limit on the fifth step (2.5 voxels of snow)
    EXPECT_EQ(marcher.columnSteps(), 6 + 5);
}

}  // namespace firn
