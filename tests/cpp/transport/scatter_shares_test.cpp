// The firn_scatter grid's coarse shares (baked_grids.h, coarsenedShares) read as Cycles reads them, trilinearly on
// voxels twice the density's: 1 over a thin lump's whole density ramp into the air, 0 beyond its reach, and the
// snow beside thin snow that does not scatter kept to half a share within one voxel of it.
#include <vector>

#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>

#include "firn/transport/baked_grids.h"
#include "firn/util/error.h"

namespace firn {

namespace {

constexpr int kScale = BakedGrids::kScatterScale;

// The share the renderer reads at density index point p from coarse shares.
float readAt(const openvdb::FloatTree &coarse, const openvdb::Vec3d &p) {
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> share(coarse);
    return openvdb::tools::BoxSampler::sample(share, p / double(kScale));
}

// Share 1 on `thin` and on the air voxels (no density) touching one of them: the bake's rule (scatterShares).
openvdb::FloatTree::Ptr sharesOf(const std::vector<openvdb::Coord> &thin, const openvdb::FloatTree &density) {
    auto shares = std::make_shared<openvdb::FloatTree>(0.0f);
    for (const openvdb::Coord &c : thin)
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz)
                    if (const openvdb::Coord n = c.offsetBy(dx, dy, dz); n == c || !(density.getValue(n) > 0.0f))
                        shares->setValue(n, 1.0f);
    return shares;
}

}  // namespace

TEST(ScatterShares, ALumpInAirScattersOverItsWholeRampAndNothingBeyondItsReach) {
    ASSERT_EQ(kScale, 2);
    for (const openvdb::Coord c : {openvdb::Coord(0, 0, 0), openvdb::Coord(1, 0, 0), openvdb::Coord(1, 1, 1),
                                   openvdb::Coord(-3, 2, 5)}) {  // each parity of the coarse voxels' lattice
        openvdb::FloatTree density(0.0f);
        density.setValue(c, 50.0f);
        const openvdb::FloatTree::Ptr coarse = coarsenedShares(*sharesOf({c}, density), density, kScale);
        // Its density ramp: trilinear from its centre to its neighbours' (air) centres.
        for (double x = -1.0; x <= 1.0; x += 0.25)
            for (double y = -1.0; y <= 1.0; y += 0.25)
                for (double z = -1.0; z <= 1.0; z += 0.25)
                    EXPECT_FLOAT_EQ(readAt(*coarse, c.asVec3d() + openvdb::Vec3d(x, y, z)), 1.0f) << c;
        // The air ring's coarse hats reach 2 voxels past it, no further.
        EXPECT_EQ(readAt(*coarse, c.asVec3d() + openvdb::Vec3d(4.0, 0.0, 0.0)), 0.0f) << c;
        EXPECT_EQ(readAt(*coarse, c.asVec3d() + openvdb::Vec3d(0.0, -4.0, 4.0)), 0.0f) << c;
    }
}

TEST(ScatterShares, SnowBesideThinSnowScattersAtMostHalfWithinOneVoxel) {
    // Thick snow at x <= last, thin snow two voxels deep on it, air beyond; the read along x through the middle,
    // for both parities of the boundary. Where a coarse voxel lies on snow it holds that voxel's share, on air
    // the largest share its hat touches: the thick snow reads 0 but in its last voxel on odd boundaries (1/2),
    // and there the first thin voxel reads 1/2 too.
    for (const int last : {9, 10}) {
        openvdb::FloatTree density(0.0f);
        std::vector<openvdb::Coord> thin;
        for (int y = 0; y <= 9; ++y)
            for (int z = 0; z <= 9; ++z) {
                for (int x = 0; x <= last; ++x) density.setValue(openvdb::Coord(x, y, z), 300.0f);
                for (int x = last + 1; x <= last + 2; ++x) {
                    density.setValue(openvdb::Coord(x, y, z), 10.0f);
                    thin.emplace_back(x, y, z);
                }
            }
        const openvdb::FloatTree::Ptr coarse = coarsenedShares(*sharesOf(thin, density), density, kScale);
        const bool odd = last % 2 == 1;
        // x = last - 1 ... last + 5: thick, thick, thin, thin, air (ring), air, air
        const std::vector<float> expected = odd ? std::vector<float>{0.0f, 0.5f, 1.0f, 1.0f, 1.0f, 0.5f, 0.0f}
                                                : std::vector<float>{0.0f, 0.0f, 0.5f, 1.0f, 1.0f, 1.0f, 0.5f};
        for (int i = 0; i < int(expected.size()); ++i)
            EXPECT_FLOAT_EQ(readAt(*coarse, openvdb::Vec3d(last - 1 + i, 4.0, 5.0)), expected[i]) << last << " " << i;
        for (int x = 0; x < last - 1; ++x) EXPECT_EQ(readAt(*coarse, openvdb::Vec3d(x, 4.0, 5.0)), 0.0f);
    }
}

TEST(ScatterShares, AtTheDensitysOwnVoxelsTheSharesAreKept) {
    openvdb::FloatTree density(0.0f);
    const std::vector<openvdb::Coord> thin{openvdb::Coord(-3, -6, 1), openvdb::Coord(4, 8, 1)};
    for (const openvdb::Coord &c : thin) density.setValue(c, 10.0f);
    const openvdb::FloatTree::Ptr fine = sharesOf(thin, density);
    const openvdb::FloatTree::Ptr same = coarsenedShares(*fine, density, 1);
    EXPECT_EQ(same->activeVoxelCount(), fine->activeVoxelCount());
    for (auto it = fine->cbeginValueOn(); it; ++it) EXPECT_EQ(same->getValue(it.getCoord()), *it);
    EXPECT_THROW(coarsenedShares(*fine, density, 0), InvalidArgument);
}

}  // namespace firn
