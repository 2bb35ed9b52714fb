#include "firn/transport/traced_source.h"

#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/util/sampling.h"

namespace firn {

// A source the stored form holds exactly (a peaked lobe about the beams' axis plus a linear broad lobe), gathered
// without noise in every direction: the fit by direction finds its parts again (k on the fit's 0.01 steps).
TEST(FitByDirection, RecoversASourceTheStoredFormHolds) {
    const glm::dvec3 m = glm::normalize(glm::dvec3(0.3, -0.4, -0.866)), l1(0.04, -0.03, 0.05);
    constexpr double kPeak = 0.6, kK = 0.8, kL0 = 0.3;  // W/m^2/sr
    const SourceDirections directions = sourceDirections(m);
    SourceEstimate S;
    S.l0 = glm::dvec3(kPeak + kL0);  // the source's mean over directions (4 pi HG has mean 1)
    for (int j = 0; j < kSourceDirections; ++j)
        S.toward[j] = kPeak * 4.0 * kPi * henyeyGreenstein(glm::dot(directions[j], m), kK) + kL0 + glm::dot(l1, directions[j]);
    Source flat;
    flat.l0 = glm::vec3(float(kPeak + kL0));
    DirectionWeights seen;
    seen.fill(1.0);
    const std::optional<Source> fit = fitByDirection(S, directions, seen, m, 0.87, flat);
    ASSERT_TRUE(fit.has_value());
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(fit->peak0[c], kPeak, 1e-4);
        EXPECT_NEAR(fit->l0[c], kL0, 1e-4);
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(fit->l1[c][a], l1[a], 1e-4);
        EXPECT_NEAR(fit->peak1[c], 3.0 * kK * kPeak * m[c], 1e-4);  // 3 k m mean(p0)
    }
}

TEST(FitByDirection, NoneWithoutLight) {
    const SourceDirections directions = sourceDirections(glm::dvec3(0.0, 0.0, -1.0));
    DirectionWeights seen;
    seen.fill(1.0);
    EXPECT_FALSE(fitByDirection(SourceEstimate{}, directions, seen, glm::dvec3(0.0, 0.0, -1.0), 0.87, Source{}).has_value());
}

// A wide slab of 8 layers, optical depth 1 per voxel: a voxel of the top layer is seen from above through less
// than one optical depth and from below through the other seven; from the side, through more than the cap of 10.
TEST(VisibilityFrom, FallsWithTheSnowAlongEachDirection) {
    constexpr double kVoxel = 0.01, kDensity = 100.0;  // m, kg/m^3
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setTransform(openvdb::math::Transform::createLinearTransform(kVoxel));
    density->fill(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(39, 39, 7)), float(kDensity));
    const Medium medium(density, VolumeOptics{1.0 / (kDensity * kVoxel), Rgb(0.99), 0.87});  // tau 1 per voxel
    Medium::ColumnMarcher marcher(medium);
    const SourceDirections directions = sourceDirections(glm::dvec3(0.0, 0.0, -1.0));
    const DirectionWeights top = visibilityFrom(medium, marcher, openvdb::Coord(20, 20, 7), directions);
    for (int j = 0; j < kSourceDirections; ++j) {
        const glm::dvec3 &w = directions[j];
        if (w.z > 0.5) {
            EXPECT_GT(top[j], std::exp(-1.0)) << j;
        } else if (w.z < -0.5) {
            EXPECT_LT(top[j], std::exp(-6.0)) << j;
        } else if (w.z == 0.0) {
            EXPECT_LE(top[j], std::exp(-9.9)) << j;
        }
    }
}

}  // namespace firn
