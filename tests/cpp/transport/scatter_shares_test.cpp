// The firn_scatter grid's scattered density (baked_grids.h, scatteredDensity) read as Cycles reads it, trilinearly on
// voxels twice the density's, and the share of the extinction the renderer then scatters (scatteredShare): all of a
// thin lump's density over its whole ramp into the air, nothing beyond its reach, and no more of the snow beside
// thin snow that does not scatter than the thin snow's own density.
#include <vector>

#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>

#include "firn/transport/baked_grids.h"
#include "firn/transport/joint_medium.h"
#include "firn/util/error.h"

namespace firn {

namespace {

constexpr int kScale = BakedGrids::kScatterScale;

// A tree read trilinearly (as Cycles reads a grid) at index point p of a grid `scale` times finer.
double trilinear(const openvdb::FloatTree &tree, const openvdb::Vec3d &p, int scale = 1) {
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> values(tree);
    return openvdb::tools::BoxSampler::sample(values, p / double(scale));
}

// The scattered density (kg/m^3) the renderer reads at density index point p from the coarse grid.
double scatteredAt(const openvdb::FloatTree &coarse, const openvdb::Vec3d &p) { return trilinear(coarse, p, kScale); }

// On at `thin`: the voxels the bake lets the renderer scatter (scatterMask).
openvdb::BoolTree::Ptr maskOf(const std::vector<openvdb::Coord> &thin) {
    auto mask = std::make_shared<openvdb::BoolTree>(false);
    for (const openvdb::Coord &c : thin) mask->setValueOn(c, true);
    return mask;
}

}  // namespace

TEST(ScatterShares, ALumpInAirScattersAllItsDensityOverItsWholeRampAndNothingBeyondItsReach) {
    ASSERT_EQ(kScale, 2);
    for (const openvdb::Coord c : {openvdb::Coord(0, 0, 0), openvdb::Coord(1, 0, 0), openvdb::Coord(1, 1, 1),
                                   openvdb::Coord(-3, 2, 5)}) {  // each parity of the coarse voxels' lattice
        // Two voxels of unequal density, so a coarse voxel's largest value is not every fine voxel's.
        const openvdb::Coord d = c.offsetBy(1, 0, 0);
        openvdb::FloatTree density(0.0f);
        density.setValue(c, 50.0f), density.setValue(d, 20.0f);
        const openvdb::FloatTree::Ptr coarse = scatteredDensity(*maskOf({c, d}), density, kScale);
        // Their density ramp: trilinear from their centres to their neighbours' (air) centres.
        for (double x = -1.0; x <= 2.0; x += 0.25)
            for (double y = -1.0; y <= 1.0; y += 0.25)
                for (double z = -1.0; z <= 1.0; z += 0.25) {
                    const openvdb::Vec3d p = c.asVec3d() + openvdb::Vec3d(x, y, z);
                    if (const double rho = trilinear(density, p); rho > 0.0) {
                        EXPECT_DOUBLE_EQ(scatteredShare(rho, scatteredAt(*coarse, p)), 1.0) << c << " " << p;
                    }
                }
        // The coarse hats reach 2 coarse voxels past the lump's, no further: 4 density voxels.
        EXPECT_EQ(scatteredAt(*coarse, c.asVec3d() + openvdb::Vec3d(-4.0, 0.0, 0.0)), 0.0) << c;
        EXPECT_EQ(scatteredAt(*coarse, d.asVec3d() + openvdb::Vec3d(4.0, 0.0, 0.0)), 0.0) << c;
        EXPECT_EQ(scatteredAt(*coarse, c.asVec3d() + openvdb::Vec3d(0.0, -4.0, 4.0)), 0.0) << c;
    }
}

TEST(ScatterShares, SnowBesideThinSnowScattersNoMoreThanTheThinSnowsDensity) {
    // Thick snow (300 kg/m^3) at x <= last, thin snow (10) two voxels deep on it, air beyond; read along x through
    // the middle, for both parities of the boundary. The thin snow scatters whole; in the thick snow the renderer
    // scatters at most the thin snow's 10 kg/m^3 (a share read trilinearly scattered half of the thick voxel beside
    // it: its light is the surface's, and the renderer scattered it again, docs/benchmarks.md lead-95), and nothing
    // four voxels in.
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
        const openvdb::FloatTree::Ptr coarse = scatteredDensity(*maskOf(thin), density, kScale);
        for (double x = last - 6.0; x <= last + 3.0; x += 0.125) {
            const openvdb::Vec3d p(x, 4.0, 5.0);
            const double rho = trilinear(density, p), share = scatteredShare(rho, scatteredAt(*coarse, p));
            if (x >= last + 1.0 && rho > 0.0) {
                EXPECT_DOUBLE_EQ(share, 1.0) << last << " " << x;
            }
            EXPECT_LE(share * rho, 10.0 * (1.0 + 1e-6)) << last << " " << x;
            if (x <= last - 4.0) {
                EXPECT_EQ(share, 0.0) << last << " " << x;
            }
        }
        EXPECT_GT(scatteredShare(300.0, scatteredAt(*coarse, openvdb::Vec3d(last, 4.0, 5.0))), 0.0) << last;
    }
}

TEST(ScatterShares, AtTheDensitysOwnVoxelsEachTakesTheLargestScatteredDensityBesideIt) {
    openvdb::FloatTree density(0.0f);
    const std::vector<openvdb::Coord> thin{openvdb::Coord(-3, -6, 1), openvdb::Coord(4, 8, 1)};
    density.setValue(thin[0], 10.0f), density.setValue(thin[1], 30.0f);
    density.setValue(openvdb::Coord(4, 8, 2), 300.0f);  // thick snow beside the second, not scattered
    const openvdb::FloatTree::Ptr fine = scatteredDensity(*maskOf(thin), density, 1);
    EXPECT_EQ(fine->activeVoxelCount(), 2 * 27);
    EXPECT_EQ(fine->getValue(openvdb::Coord(-4, -5, 2)), 10.0f);
    EXPECT_EQ(fine->getValue(openvdb::Coord(4, 8, 2)), 30.0f);
    EXPECT_EQ(fine->getValue(openvdb::Coord(4, 8, 3)), 0.0f);
    EXPECT_DOUBLE_EQ(scatteredShare(300.0, 30.0), 0.1);
    EXPECT_EQ(scatteredShare(0.0, 30.0), 0.0);  // air: no extinction to share
    EXPECT_THROW(scatteredDensity(*maskOf(thin), density, 0), InvalidArgument);
}

TEST(ScatterShares, ObjectsBakedAsOneMediumScatterEachItsOwnSnowBesideThinSnowAsOneObjectWould) {
    // bakedGridsOf (joint_medium.h): thick snow A (300 kg/m^3, x <= 9) under thin snow of A and B (5 each, x = 10, 11:
    // the union's thin voxels, which the renderer scatters), and B's edge lying in A's top voxels (20, x = 8, 9). B is
    // written on voxels shifted one along x (its own transform, resampled onto the union's). In the thin snow each
    // object scatters whole; beside it each scatters at most its own thin snow's density, so together at most the
    // union's 10, as one object of that snow would. The union's scattered density divided by each object's own
    // (before stop 96) let B scatter half its edge there besides A's share: 20 kg/m^3 at x = 9.
    const openvdb::math::Transform::Ptr voxels = openvdb::math::Transform::createLinearTransform(0.01);
    const openvdb::math::Transform::Ptr shifted = voxels->copy();
    shifted->postTranslate(openvdb::Vec3d(0.01, 0.0, 0.0));  // B's voxel x is the union's x + 1
    openvdb::FloatGrid::Ptr a = openvdb::FloatGrid::create(0.0f), b = openvdb::FloatGrid::create(0.0f);
    a->setTransform(voxels), b->setTransform(shifted);
    std::vector<openvdb::Coord> thin;
    for (int y = 0; y <= 9; ++y)
        for (int z = 0; z <= 9; ++z) {
            for (int x = 0; x <= 9; ++x) a->tree().setValue(openvdb::Coord(x, y, z), 300.0f);
            for (int x = 10; x <= 11; ++x) {
                a->tree().setValue(openvdb::Coord(x, y, z), 5.0f);
                b->tree().setValue(openvdb::Coord(x - 1, y, z), 5.0f);
                thin.emplace_back(x, y, z);
            }
            for (int x = 8; x <= 9; ++x) b->tree().setValue(openvdb::Coord(x - 1, y, z), 20.0f);
        }
    const openvdb::FloatGrid::Ptr both = unionDensity({a, b});
    BakedGrids joint;
    for (auto &source : joint.source) {
        source = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
        source->setTransform(voxels->copy());
        source->tree().setValue(openvdb::Coord(5, 5, 5), openvdb::Vec3f(1.0f));
    }
    joint.scattered = openvdb::BoolGrid::create(maskOf(thin));
    joint.scattered->setTransform(voxels->copy());
    joint.scatter = openvdb::FloatGrid::create(scatteredDensity(*maskOf(thin), both->tree(), kScale));
    const BakedGrids alone[2] = {bakedGridsOf(joint, *a), bakedGridsOf(joint, *b)};
    const openvdb::FloatGrid *own[2] = {a.get(), b.get()};
    for (double x = 3.0; x <= 13.0; x += 0.125) {
        const openvdb::Vec3d p(x, 4.0, 5.0);  // the union's index space
        double together = 0.0;
        for (int i = 0; i < 2; ++i) {
            const openvdb::Vec3d q = own[i]->worldToIndex(voxels->indexToWorld(p));
            const double rho = trilinear(own[i]->tree(), q);
            const double scattered = rho * scatteredShare(rho, scatteredAt(alone[i].scatter->tree(), p));
            if (x >= 10.0 && x <= 11.0) {
                EXPECT_DOUBLE_EQ(scattered, rho) << i << " " << x;
            }
            EXPECT_LE(scattered, 5.0 * (1.0 + 1e-6)) << i << " " << x;
            together += scattered;
        }
        EXPECT_LE(together, 10.0 * (1.0 + 1e-6)) << x;
    }
    EXPECT_NEAR(trilinear(both->tree(), openvdb::Vec3d(9.0, 4.0, 5.0)), 320.0, 1e-3);  // B's edge does lie in A
}

}  // namespace firn
