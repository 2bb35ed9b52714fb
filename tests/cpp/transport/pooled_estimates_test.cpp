// Pooling light-traced voxels' source by direction over a flat uniform layer (pooled_estimates.h): which voxels
// pool, over which neighbours, and that each keeps its own amount.
#include <algorithm>

#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/transport/pooled_estimates.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.01;               // m
constexpr double kExtinctionPerDensity = 10;  // m^2/kg: density 19.5 kg/m^3 is an optical depth of 1.95 per voxel

// A 5^3 block of uniform snow, traced voxel by voxel: each voxel's l0 and source by direction differ, so that a
// pooled value tells which voxels went into it.
struct Block {
    std::shared_ptr<Medium> medium;
    openvdb::Int32Tree index{-1};
    std::vector<openvdb::Coord> voxels;
    std::vector<SourceEstimate> estimates;

    // `thick`, if given, holds `thickDensity` instead.
    explicit Block(float density, const openvdb::Coord *thick = nullptr, float thickDensity = 0.0f) {
        auto grid = test::densityGrid(kVoxel);
        for (int i = 0; i < 125; ++i) {
            const openvdb::Coord c(i % 5, i / 5 % 5, i / 25);
            grid->tree().setValue(c, thick && c == *thick ? thickDensity : density);
            index.setValue(c, i);
            voxels.push_back(c);
            SourceEstimate S;
            S.l0 = Rgb(1.0 + i % 3);
            for (int j = 0; j < kSourceDirections; ++j) S.toward[j] = (i + 1) * (j + 1);
            estimates.push_back(S);
        }
        medium = std::make_shared<Medium>(grid, VolumeOptics{kExtinctionPerDensity, Rgb(0.999), 0.85});
    }
    std::size_t at(const openvdb::Coord &c) const { return std::size_t(index.getValue(c)); }
};

// What pooling over `pooled` (the voxel itself among them) gives the voxel `own` towards direction j.
double pooledToward(const Block &b, std::size_t own, const std::vector<std::size_t> &pooled, int j) {
    double l0 = 0.0, toward = 0.0;
    for (std::size_t v : pooled) l0 += b.estimates[v].l0.x, toward += b.estimates[v].toward[j];
    return b.estimates[own].l0.x / l0 * toward;
}

std::vector<std::size_t> blockAround(const Block &b, const openvdb::Coord &centre) {
    std::vector<std::size_t> out;
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) out.push_back(b.at(centre.offsetBy(dx, dy, dz)));
    return out;
}

}  // namespace

// Inside the block a voxel pools over all 27; a corner (7 neighbours, fewer than a flat face's 17) keeps its own;
// every voxel keeps its own l0.
TEST(PooledEstimates, PoolsInsideAUniformLayerAndKeepsCornersAndAmounts) {
    const Block b(19.5f);
    const std::vector<SourceEstimate> out = pooledEstimates(*b.medium, b.index, b.voxels, b.estimates);
    const std::size_t centre = b.at(openvdb::Coord(2, 2, 2)), corner = b.at(openvdb::Coord(0, 0, 0));
    for (int j = 0; j < kSourceDirections; ++j) {
        EXPECT_NEAR(out[centre].toward[j], pooledToward(b, centre, blockAround(b, openvdb::Coord(2, 2, 2)), j),
                    1e-9 * out[centre].toward[j]);
        EXPECT_EQ(out[corner].toward[j], b.estimates[corner].toward[j]);
    }
    for (std::size_t v = 0; v < b.voxels.size(); ++v) EXPECT_EQ(out[v].l0, b.estimates[v].l0);
}

// A neighbour of nearly the same density but just over kMaxDirectionFitTau is not fitted by direction (its
// `toward` stays 0 in light tracing): it takes no part, or its l0 would dilute the pool.
TEST(PooledEstimates, LeavesOutNeighboursNotFittedByDirection) {
    const openvdb::Coord thick(2, 2, 3);
    Block b(19.5f, &thick, 21.0f);  // optical depths 1.95 and 2.1: within the pooled density ratio, one not fitted
    b.estimates[b.at(thick)].toward.fill(0.0);
    const std::vector<SourceEstimate> out = pooledEstimates(*b.medium, b.index, b.voxels, b.estimates);
    std::vector<std::size_t> pooled = blockAround(b, openvdb::Coord(2, 2, 2));
    pooled.erase(std::find(pooled.begin(), pooled.end(), b.at(thick)));
    const std::size_t centre = b.at(openvdb::Coord(2, 2, 2));
    for (int j = 0; j < kSourceDirections; ++j)
        EXPECT_NEAR(out[centre].toward[j], pooledToward(b, centre, pooled, j), 1e-9 * out[centre].toward[j]);
    EXPECT_EQ(out[b.at(thick)].toward, b.estimates[b.at(thick)].toward);
}

}  // namespace firn
