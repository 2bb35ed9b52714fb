#include "firn/transport/diffusion_links.h"

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace firn {

namespace {

// A block of nx x ny x nz voxels with every third voxel of a diagonal pattern missing (holes, so links end at
// faces), unknowns in x-major order as the topology's, densities drawn at random (as the car's: all distinct).
struct Block {
    VoxelLinks link;
    UnwrittenVector<float> density;
};
Block holedBlock(int nx, int ny, int nz, std::uint32_t seed) {
    std::vector<std::int32_t> index(std::size_t(nx) * ny * nz, -1);
    auto at = [&](int x, int y, int z) -> std::int32_t & { return index[(std::size_t(x) * ny + y) * nz + z]; };
    Block block;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> rho(100.0f, 450.0f);  // kg/m^3, snow
    for (int x = 0; x < nx; ++x)
        for (int y = 0; y < ny; ++y)
            for (int z = 0; z < nz; ++z)
                if ((x + 2 * y + z) % 3 != 0 || z == 0) at(x, y, z) = std::int32_t(block.density.size()), block.density.push_back(rho(rng));
    block.link.resize(block.density.size());
    for (int x = 0; x < nx; ++x)
        for (int y = 0; y < ny; ++y)
            for (int z = 0; z < nz; ++z) {
                const std::int32_t i = at(x, y, z);
                if (i < 0) continue;
                const int c[3] = {x, y, z}, n[3] = {nx, ny, nz};
                for (int f = 0; f < 6; ++f) {
                    int d[3] = {c[0], c[1], c[2]};
                    d[f / 2] += f & 1 ? 1 : -1;
                    const bool inside = d[f / 2] >= 0 && d[f / 2] < n[f / 2];
                    block.link[i][f] = inside ? at(d[0], d[1], d[2]) : -1;
                }
            }
    return block;
}

}  // namespace

// The assembly reads each interior link from SharedLinks, which computes a link once for both its ends: every link
// must be interiorLink's own, bit for bit, whatever runs the unknowns are split into (the bake's grids were measured
// with each end computing its own). Runs of 1 (every lower link computed anew), 7, 64 and the whole block.
TEST(SharedLinks, EveryLinkIsInteriorLinksOwnBitForBit) {
    const Block block = holedBlock(9, 8, 7, 12345);
    const double h = 0.02, beta = 0.0871, sigmaTrPerDensity = 2.9;  // m; kappa D; m^2/kg (a red channel's values)
    const std::size_t n = block.density.size();
    int links = 0;
    for (const std::size_t run : {std::size_t(1), std::size_t(7), std::size_t(64), n}) {
        for (std::size_t begin = 0; begin < n; begin += run) {
            const std::size_t end = std::min(n, begin + run);
            const SharedLinks shared(block.link, block.density, sigmaTrPerDensity, beta, h, begin, end);
            for (std::size_t i = begin; i < end; ++i)
                for (int f = 0; f < 6; ++f) {
                    const std::int32_t j = block.link[i][f];
                    if (j < 0) continue;
                    const Link expected = interiorLink(
                        beta, 1.5 * h * (sigmaTrPerDensity * block.density[i] + sigmaTrPerDensity * block.density[j]));
                    const Link got = shared.at(i, f);
                    ASSERT_EQ(expected.conductance, got.conductance) << "unknown " << i << " face " << f;
                    ASSERT_EQ(expected.halfMass, got.halfMass) << "unknown " << i << " face " << f;
                    ++links;
                }
        }
    }
    EXPECT_GT(links, 4 * 1000);  // the block holds over a thousand links, each seen from both ends in each split
}

}  // namespace firn
