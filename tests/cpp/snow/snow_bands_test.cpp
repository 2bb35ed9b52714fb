// Snow with levels of detail (snow_bands.h): each band at its voxel size and distances, the same snow on both
// sides of a band boundary, budgets refused before the work.
#include "firn/snow/snow_bands.h"

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>

#include "firn/util/error.h"
#include "test_geometry.h"

namespace firn {

namespace {

// 20 cm of snow at 2 cm voxels, seen along +y from 1 m above the plane, 4 mrad per pixel: bands start at
// 10, 20, 40 m.
SnowLayerSettings deepSnow() {
    SnowLayerSettings s;
    s.depth = 0.2;
    s.spacing = 0.1;
    s.voxelSize = 0.02;
    s.exposureRays = 4;
    return s;
}

CameraFootprint alongY() {
    CameraFootprint c;
    c.position = {0.0, -2.0, 1.0};
    c.forward = {0.0, 1.0, 0.0};
    c.pixelAngle = 4e-3;
    c.viewHalfAngle = 0.3;
    return c;
}

// Height (m) of the snow's top above (x, y): the level set's zero crossing, scanned down from `from`; NaN if none.
double topHeight(const openvdb::FloatGrid &surface, double x, double y, double from) {
    const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(surface);
    const double step = 0.25 * surface.voxelSize()[0];
    double above = sampler.wsSample(openvdb::Vec3d(x, y, from));
    for (double z = from - step; z > -1.0; z -= step) {
        const double value = sampler.wsSample(openvdb::Vec3d(x, y, z));
        if (value <= 0.0 && above > 0.0) return z + step * value / (value - above);
        above = value;
    }
    return std::numeric_limits<double>::quiet_NaN();
}

const SnowBands &planeSnow() {
    static const SnowBands snow = generateSnowBands(test::plane(100.0f, {0.0f, 48.0f, 0.0f}), {}, deepSnow(),
                                                    alongY(), nullptr);
    return snow;
}

}  // namespace

// Each band's grids are at its level's voxel size, and its snow lies within its distances.
TEST(SnowBands, EachBandAtItsVoxelSizeAndDistances) {
    const SnowBands &snow = planeSnow();
    const CameraFootprint camera = alongY();
    ASSERT_GE(snow.bands.size(), 4u);  // 10, 20, 40 m and beyond within the 100 m plane
    for (const SnowBand &b : snow.bands) {
        EXPECT_DOUBLE_EQ(b.grids.density->voxelSize()[0], 0.02 * std::ldexp(1.0, b.band.level));
        EXPECT_DOUBLE_EQ(b.grids.surface->voxelSize()[0], b.band.voxelSize);
        for (auto it = b.grids.density->cbeginValueOn(); it; ++it) {
            const openvdb::Vec3d p = b.grids.density->indexToWorld(it.getCoord());
            const double d = glm::length(glm::dvec3(p.x(), p.y(), p.z()) - camera.position);
            ASSERT_GE(d, b.band.nearDistance);
            ASSERT_LT(d, b.band.farDistance);
        }
    }
    EXPECT_GT(snow.outOfView, 0u);  // the plane's sides and the part behind the camera
}

// Where two bands meet, both describe the same snow: the tops agree within the coarser voxel, and lie at the
// layer's depth (open level ground: full cover).
TEST(SnowBands, DepthAgreesAcrossBandBoundaries) {
    const SnowBands &snow = planeSnow();
    const CameraFootprint camera = alongY();
    for (std::size_t k = 0; k + 1 < snow.bands.size(); ++k) {
        const SnowBand &fine = snow.bands[k], &coarse = snow.bands[k + 1];
        const double boundary = fine.band.farDistance;  // m from the camera
        const double ground = std::sqrt(boundary * boundary - camera.position.z * camera.position.z);
        for (double angle : {-0.2, -0.1, 0.0, 0.1, 0.2}) {
            const double x = ground * std::sin(angle), y = camera.position.y + ground * std::cos(angle);
            const double a = topHeight(*fine.grids.surface, x, y, 0.6);
            const double b = topHeight(*coarse.grids.surface, x, y, 0.6);
            EXPECT_NEAR(a, b, coarse.band.voxelSize) << "bands " << k << ", " << k + 1 << " at angle " << angle;
            EXPECT_NEAR(b, 0.2, 0.25 * 0.2 + coarse.band.voxelSize);  // depth, jittered by randomness 0.25
        }
    }
}

TEST(SnowBands, Deterministic) {
    const SnowBands again = generateSnowBands(test::plane(100.0f, {0.0f, 48.0f, 0.0f}), {}, deepSnow(), alongY(),
                                              nullptr);
    const SnowBands &snow = planeSnow();
    ASSERT_EQ(again.metaballs.size(), snow.metaballs.size());
    for (std::size_t i = 0; i < snow.metaballs.size(); ++i) ASSERT_EQ(again.metaballs[i].centre, snow.metaballs[i].centre);
    ASSERT_EQ(again.bands.size(), snow.bands.size());
    for (std::size_t k = 0; k < snow.bands.size(); ++k)
        EXPECT_EQ(again.bands[k].grids.density->activeVoxelCount(), snow.bands[k].grids.density->activeVoxelCount());
}

// A 1 km plane: refused at once under a small budget (the bound comes before any site), and a plane that
// the uniform grid refuses is accepted with levels of detail.
TEST(SnowBands, KilometrePlaneRefusedByBoundOrFitted) {
    const TriangleMesh plane = test::plane(1000.0f);
    CameraFootprint camera;
    camera.position = {0.0, -480.0, 1.7};
    camera.forward = {0.0, 1.0, 0.0};
    camera.pixelAngle = 0.70 / 200.0;  // 40 degrees over 200 pixels
    camera.viewHalfAngle = 0.45;
    SnowLayerSettings s;
    s.exposureRays = 4;
    s.maxVoxels = 1e5;
    try {
        generateSnowBands(plane, {}, s, camera, nullptr);
        FAIL() << "a 1e5 voxel budget cannot hold a 1 km plane";
    } catch (const BudgetExceeded &e) {
        EXPECT_NE(std::string(e.what()).find("at least (with levels of detail)"), std::string::npos) << e.what();
    }
    s.maxVoxels = 50e6;
    EXPECT_THROW(generateSnowLayer(plane, {}, s, nullptr), BudgetExceeded);
    const SnowBands snow = generateSnowBands(plane, {}, s, camera, nullptr);
    double active = 0.0;
    for (const SnowBand &b : snow.bands) active += double(b.grids.density->activeVoxelCount());
    EXPECT_LE(active, s.maxVoxels);
    EXPECT_GE(snow.bands.size(), 6u);
}

}  // namespace firn
