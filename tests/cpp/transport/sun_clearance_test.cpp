// SunClearance (sun_clearance.h): a point it clears has no occluder on any shadow ray towards the sun's disc, and it
// clears the points in open air above the occluders. The oracle is Embree's own query (RayCaster::occluded, as beamAt
// asks it: from the point rounded to float, tNear 1e-5) along the sun's axis, directions spread over its disc and
// directions on the disc's rim.
#include <cmath>
#include <random>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/geometry/mesh.h"
#include "firn/transport/scene.h"
#include "firn/transport/sun_clearance.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.01;  // m

// Snow from voxel -6 to 6 on each axis (its two corners), so the pre-test's grid spans the points below.
Medium block() {
    auto grid = test::densityGrid(kVoxel);
    grid->getAccessor().setValue(openvdb::Coord(-6), 100.0f);
    grid->getAccessor().setValue(openvdb::Coord(6), 100.0f);
    return Medium(grid, VolumeOptics{1.0, Rgb(0.9), 0.6});
}

Occluders triangles(const std::vector<glm::dvec3> &corners) {  // voxels, three per triangle
    std::vector<float> v;
    std::vector<unsigned> t;
    for (const glm::dvec3 &p : corners) {
        for (int k = 0; k < 3; ++k) v.push_back(float(p[k] * kVoxel));
        t.push_back(unsigned(t.size()));
    }
    return Occluders(makeTriangleMesh(v.data(), corners.size(), t.data(), corners.size() / 3),
                     std::vector<Rgb>(corners.size() / 3, Rgb(0.5)));
}

SunLight sunFrom(double elevation, double azimuth, double angularDiameter) {  // rad
    SunLight sun;
    sun.direction = {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                     std::sin(elevation)};
    sun.irradiance = Rgb(1.0);
    sun.angularDiameter = angularDiameter;
    return sun;
}

// Whether any shadow ray from p towards the sun's disc meets an occluder: the axis, 64 directions over the disc and
// 32 on its rim.
bool anyShadowRayHits(const Occluders &occluders, const SunLight &sun, const glm::dvec3 &p) {
    const RayCaster &caster = occluders.caster();
    const auto hits = [&](const glm::dvec3 &w) { return caster.occluded(glm::vec3(p), glm::vec3(w), 1e-5f); };
    if (hits(sun.direction)) return true;
    if (sun.angularDiameter <= 0.0) return false;
    const double rim = std::cos(0.5 * sun.angularDiameter);
    for (int k = 0; k < 64; ++k)
        if (hits(sampleUniformCone(sun.direction, rim, (k / 8 + 0.5) / 8.0, (k % 8 + 0.5) / 8.0))) return true;
    for (int k = 0; k < 32; ++k)
        if (hits(sampleUniformCone(sun.direction, rim, 0.0, k / 32.0))) return true;
    return false;
}

struct Points {
    int cleared = 0, hit = 0, all = 0;
    bool wrong = false;  // a cleared point with a hit
};

Points testPoints(const Medium &medium, const Occluders &occluders, const SunLight &sun,
                  const std::vector<glm::dvec3> &points) {
    const SunClearance clearance(medium, occluders, sun);
    Points out;
    for (const glm::dvec3 &p : points) {
        const bool cleared = clearance.clear(p), hit = anyShadowRayHits(occluders, sun, p);
        out.cleared += cleared, out.hit += hit, ++out.all;
        out.wrong |= cleared && hit;
    }
    return out;
}

}  // namespace

TEST(SunClearance, ClearsNoPointWithAHitUnderRandomTriangles) {
    // Triangles with corners on half voxels, jittered by 0 or up to 1e-6 voxels (edges and planes shared with the
    // points'), and points on the same lattice, just above and below the triangles' corners along the sun, and just
    // under and over their middles.
    const Medium medium = block();
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> halves(-10, 10);
    std::uniform_real_distribution<double> jitter(-1e-6, 1e-6), unit(0.0, 1.0);
    std::bernoulli_distribution jittered(0.5);
    const auto lattice = [&] {
        glm::dvec3 p;
        for (int k = 0; k < 3; ++k) p[k] = 0.5 * halves(rng) + (jittered(rng) ? jitter(rng) : 0.0);
        return p;
    };
    int cleared = 0, hit = 0, all = 0;
    for (int scene = 0; scene < 60; ++scene) {
        std::vector<glm::dvec3> corners;
        for (int t = 0; t < 3 * (1 + scene % 4); ++t) corners.push_back(lattice());
        const Occluders occluders = triangles(corners);
        const double diameters[] = {0.0, 0.0093, 0.2};
        const SunLight sun = sunFrom(0.1 + 1.4 * unit(rng), 6.3 * unit(rng), diameters[scene % 3]);
        std::vector<glm::dvec3> points;
        for (int k = 0; k < 200; ++k) points.push_back(kVoxel * lattice());
        for (const glm::dvec3 &c : corners)
            for (const double along : {-1e-4, 0.0, 1e-6, 1e-4, 0.01, 0.5})
                points.push_back(kVoxel * (c + along * sun.direction));
        // Just under and over each triangle's middle: those under it (beyond the rays' tNear) are in its shadow.
        for (std::size_t t = 0; t < corners.size(); t += 3) {
            const glm::dvec3 middle = (corners[t] + corners[t + 1] + corners[t + 2]) / 3.0;
            for (const double along : {-0.5, -0.005, 0.005})
                points.push_back(kVoxel * (middle + along * sun.direction));
        }
        const Points p = testPoints(medium, occluders, sun, points);
        EXPECT_FALSE(p.wrong) << "scene " << scene;
        cleared += p.cleared, hit += p.hit, all += p.all;
    }
    EXPECT_GT(hit, all / 10);     // the triangles shade points
    EXPECT_GT(cleared, all / 3);  // and the pre-test clears many of the others
}

TEST(SunClearance, ClearsThePointsAboveAPlateAndNoneInARoofsShadow) {
    // A plate at z = 0 under the points, a roof (z = 4 voxels, x < 0) over half of them; the sun 25 degrees up
    // along +x with the default disc (Blender's 0.526 degrees), so the roof shades the points with x < 0 and the
    // strip x < (4 - z) / tan 25 beyond its edge.
    const Medium medium = block();
    const Occluders occluders = triangles({{-20, -20, 0}, {20, -20, 0}, {0, 20, 0},  // the plate
                                           {-20, -20, 4}, {0, -20, 4}, {0, 20, 4},
                                           {-20, -20, 4}, {0, 20, 4}, {-20, 20, 4}});  // the roof
    const SunLight sun = sunFrom(25.0 * kPi / 180.0, 0.0, 0.00918);
    std::vector<glm::dvec3> points;
    for (int i = -5; i <= 5; ++i)
        for (const double z : {0.25, 0.5, 1.0, 2.0, 3.0}) points.push_back(kVoxel * glm::dvec3(i + 0.25, 0.0, z));
    const Points p = testPoints(medium, occluders, sun, points);
    EXPECT_FALSE(p.wrong);
    EXPECT_GT(p.hit, 0);
    // Every point beyond the roof's shadow is cleared, down to a quarter of a voxel above the plate.
    EXPECT_EQ(p.cleared, p.all - p.hit);
}

TEST(SunClearance, ClearsNothingWithoutOccludersOrForAWideDisc) {
    const Medium medium = block();
    EXPECT_FALSE(SunClearance(medium, Occluders(), sunFrom(1.0, 0.0, 0.0)).clear(glm::dvec3(0.0)));
    const Occluders plate = triangles({{-20, -20, -1}, {20, -20, -1}, {0, 20, -1}});
    EXPECT_TRUE(SunClearance(medium, plate, sunFrom(1.0, 0.0, 0.0)).clear(glm::dvec3(0.0)));
    // A disc 115 degrees wide: its rays drift across too far.
    EXPECT_FALSE(SunClearance(medium, plate, sunFrom(1.0, 0.0, 2.0)).clear(glm::dvec3(0.0)));
}

}  // namespace firn
