// The occluders' reflected radiance cached per cell (occluder_radiance.h) against closed forms: an open ground
// under sun and a uniform sky, and the ground beside and under a roof's edge.
#include <cmath>
#include <cstdio>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/occluder_radiance.h"
#include "firn/util/openvdb_library.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.02;    // m
constexpr double kAlbedo = 0.5;    // the ground's
constexpr double kRoof = 0.5;      // m, the roof's height above the ground

// A medium of one snow voxel 1 m under the ground (a scene needs one; no ray from the ground's top meets it).
std::shared_ptr<Medium> farSnow() {
    initializeOpenVdb();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setTransform(openvdb::math::Transform::createLinearTransform(kVoxel));
    grid->getAccessor().setValue(openvdb::Coord(0, 0, -50), 300.0f);
    return std::make_shared<Medium>(grid, VolumeOptics{2.0, Rgb(0.99), 0.85});
}

// The ground z = 0 (one triangle, 0, holding [-100, 50]^2) and, with `roof`, a roof kRoof above it over x < 0 (one
// triangle with its edge on x = 0 from y = -100 to 100, reaching x = -100: seen from within 1 m of its edge it stands
// for a half-plane to a few parts in 10^4 of the sky's irradiance).
Scene groundScene(bool roof, const glm::dvec3 &sun, double sunIrradiance, double sky) {
    Scene scene;
    scene.medium = farSnow();
    std::vector<float> v = {-100, -100, 0, 200, -100, 0, -100, 200, 0};
    std::vector<unsigned> t = {0, 1, 2};
    if (roof) {
        const float h = float(kRoof);
        v.insert(v.end(), {0, -100, h, 0, 100, h, -100, 0, h});
        t.insert(t.end(), {3, 4, 5});
    }
    scene.occluders = std::make_shared<Occluders>(makeTriangleMesh(v.data(), v.size() / 3, t.data(), t.size() / 3),
                                                  std::vector<Rgb>(t.size() / 3, Rgb(kAlbedo)));
    scene.suns = {SunLight{sun, Rgb(sunIrradiance), 0.0093}};
    scene.sky.radiance = Rgb(sky);
    return scene;
}

}  // namespace

// Open ground: every sky ray sees the uniform sky and the sun is unshadowed, so each cell holds the closed form
// albedo / pi (E cos(theta_sun) + pi L) whatever its rays.
TEST(OccluderRadiance, OpenGroundReflectsSunAndSkyExactly) {
    const glm::dvec3 sun = glm::normalize(glm::dvec3(0.3, 0.2, 0.9));
    const Scene scene = groundScene(false, sun, 2.0, 0.1);
    const OccluderRadiance cache(scene, 2 * kVoxel, 9, 7);
    Medium::ColumnMarcher marcher(*scene.medium);
    const double expected = kAlbedo / kPi * (2.0 * sun.z + kPi * 0.1);
    for (const glm::dvec3 q : {glm::dvec3(0.31, -0.17, 0.0), glm::dvec3(-2.0, 3.0, 0.0), glm::dvec3(0.011, 0.012, 0.0)}) {
        const glm::dvec3 L = cache.at(q, 0, glm::dvec3(0, 0, 1), marcher);
        EXPECT_NEAR(L.x, expected, 1e-6 * expected);
        EXPECT_NEAR(L.z, expected, 1e-6 * expected);
    }
}

// Beside and under a roof's edge (the sun overhead: under the roof shadowed, beside it lit), a point at x from the
// edge (x < 0 under the roof) sees the sky over the view factor of a differential strip to a 2D wedge (Modest,
// Radiative Heat Transfer, 3rd ed., 2013, section 4.3: F = (sin theta_2 - sin theta_1) / 2): here
// F = (1 + x / sqrt(x^2 + H^2)) / 2. The cells' values read at the cell's point on the ground (up to a cell from x),
// with 64 stratified rays each: bound 0.06 in F per point (F changes by at most |dF/dx| = 1 / (2 H) = 1 / m, 0.015
// over half a cell's diagonal; the roof's edge crosses about 8 of the 64 strata, a standard deviation near 0.02 in
// F), 0.005 on the mean over the 76 points (it read 0.001).
TEST(OccluderRadiance, GroundBesideARoofMatchesTheViewFactor) {
    const Scene scene = groundScene(true, glm::dvec3(0, 0, 1), 1.0, 1.0);
    const OccluderRadiance cache(scene, kVoxel, 64, 3);
    Medium::ColumnMarcher marcher(*scene.medium);
    double sumError = 0.0;
    int points = 0;
    for (int i = 0; i < 80; ++i) {
        const double x = -1.0 + 2.0 * (i + 0.5) / 80.0;
        if (std::abs(x) < 2 * kVoxel) continue;  // the sun's shadow edge within a cell
        const glm::dvec3 q(x, 0.1 * std::sin(7.0 * i), 0.0);
        const double F = 0.5 * (1.0 + x / std::hypot(x, kRoof));
        const double expected = kAlbedo / kPi * ((x > 0.0 ? 1.0 : 0.0) + kPi * F);
        const double got = cache.at(q, 0, glm::dvec3(0, 0, 1), marcher).y;
        EXPECT_NEAR(got, expected, 0.06 * kAlbedo) << "x " << x;
        sumError += got - expected, ++points;
    }
    std::printf("mean error %.5f of the sky's share over %d points\n", sumError / points / kAlbedo, points);
    EXPECT_NEAR(sumError / points, 0.0, 0.005 * kAlbedo);
}

// A cell's value depends on the cell, the triangle and the side alone: points in one cell read one value, and the
// values do not depend on the order or the threads that asked first.
TEST(OccluderRadiance, CellsAreTheSameWhoeverAsksFirst) {
    const Scene scene = groundScene(true, glm::normalize(glm::dvec3(0.4, 0.1, 0.6)), 1.0, 1.0);
    std::vector<glm::dvec3> points;
    for (int i = 0; i < 400; ++i) points.emplace_back(-1.0 + 0.005 * i, 0.3 * std::sin(3.0 * i), 0.0);
    const OccluderRadiance serial(scene, kVoxel, 9, 5), parallel(scene, kVoxel, 9, 5);
    std::vector<glm::dvec3> first(points.size()), second(points.size());
    Medium::ColumnMarcher marcher(*scene.medium);
    for (std::size_t i = points.size(); i-- > 0;) first[i] = serial.at(points[i], 0, glm::dvec3(0, 0, 1), marcher);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 8), [&](const auto &range) {
        Medium::ColumnMarcher own(*scene.medium);
        for (std::size_t i = range.begin(); i != range.end(); ++i) second[i] = parallel.at(points[i], 0, glm::dvec3(0, 0, 1), own);
    });
    for (std::size_t i = 0; i < points.size(); ++i) EXPECT_EQ(first[i], second[i]) << i;
    EXPECT_EQ(serial.cells(), parallel.cells());
    EXPECT_LT(serial.cells(), points.size());  // 5 mm apart: several points share a 2 cm cell
    const glm::dvec3 a = serial.at({0.301, 0.301, 0.0}, 0, glm::dvec3(0, 0, 1), marcher);
    EXPECT_EQ(a, serial.at({0.319, 0.319, 0.0}, 0, glm::dvec3(0, 0, 1), marcher));  // one cell
}

}  // namespace firn
