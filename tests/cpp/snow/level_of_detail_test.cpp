// Levels of detail (level_of_detail.h): voxels follow a pixel's footprint, bands tile the distances, and the
// targets split into bands are never given a band coarser than their nearest point needs.
#include "firn/snow/level_of_detail.h"

#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "test_geometry.h"

namespace firn {

namespace {

CameraFootprint cameraAt(glm::dvec3 position, double pixelAngle, double viewHalfAngle = 3.2) {
    CameraFootprint c;
    c.position = position;
    c.pixelAngle = pixelAngle;
    c.viewHalfAngle = viewHalfAngle;
    return c;
}

}  // namespace

// Fine near the camera; beyond, the coarsest power-of-two multiple of the fine voxel within a pixel's footprint
// (so between half a footprint and one), growing with distance.
TEST(LevelOfDetail, VoxelSizeFollowsThePixelFootprint) {
    const CameraFootprint camera = cameraAt({0, 0, 0}, 1e-3);
    const double fine = 0.01;
    double previous = 0.0;
    for (double d = 0.5; d < 5000.0; d *= 1.13) {
        const double h = lodVoxelSize(lodLevel(d, camera, fine, 16), fine);
        const double footprint = d * 1e-3;
        if (footprint < fine) {
            EXPECT_EQ(h, fine) << d;
        } else {
            EXPECT_LE(h, footprint * (1 + 1e-12)) << d;
            EXPECT_GT(h, 0.5 * footprint) << d;
        }
        EXPECT_GE(h, previous);
        previous = h;
    }
    EXPECT_EQ(lodVoxelSize(lodLevel(1e9, camera, fine, 4), fine), 0.08);  // capped at the last band
}

TEST(LevelOfDetail, BandsTileTheDistances) {
    const auto bands = lodBands(cameraAt({0, 0, 0}, 2e-3), 0.01, 0.05, 900.0, 16);
    ASSERT_EQ(bands.size(), 8u);  // 900 m x 2e-3 = 1.8 m per pixel: 1.28 m voxels at level 7
    EXPECT_EQ(bands.front().nearDistance, 0.0);
    EXPECT_TRUE(std::isinf(bands.back().farDistance));
    for (std::size_t k = 0; k < bands.size(); ++k) {
        EXPECT_DOUBLE_EQ(bands[k].voxelSize, 0.01 * std::ldexp(1.0, int(k)));
        EXPECT_DOUBLE_EQ(bands[k].spacing, 0.05 * std::ldexp(1.0, int(k)));
        if (k == 0) continue;
        EXPECT_DOUBLE_EQ(bands[k].nearDistance, bands[k - 1].farDistance);
        EXPECT_DOUBLE_EQ(bands[k].nearDistance * 2e-3, bands[k].voxelSize);  // a pixel spans a voxel
    }
}

// A 1 km plane seen from 1.7 m above its middle: every piece lies in a band no coarser than its nearest point
// needs, the pieces keep the whole area when the view is all around, and splitting stays cheap.
TEST(LevelOfDetail, SplitTargetsNeverCoarserThanAPixel) {
    const TriangleMesh plane = test::plane(1000.0f);
    const CameraFootprint camera = cameraAt({10, 20, 1.7}, 1.4e-3);
    const auto bands = lodBands(camera, 0.01, 0.05, 800.0, 16);
    const BandTargets split = splitTargetsByBand(plane, {}, camera, bands, 0.01);
    double area = 0.0;
    std::size_t pieces = 0;
    for (std::size_t k = 0; k < bands.size(); ++k) {
        const TriangleMesh &mesh = split.meshes[k];
        pieces += mesh.triangleCount();
        for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
            area += mesh.area(t);
            double nearest = 1e30;
            for (int i = 0; i < 3; ++i)
                nearest = std::min(nearest, glm::length(glm::dvec3(mesh.vertex(t, i)) - camera.position));
            // The piece's nearest vertex is at least its band's start (less a few spacings: small straddlers).
            EXPECT_GE(nearest + 8.0 * bands[k].spacing, bands[k].nearDistance) << k;
        }
    }
    EXPECT_NEAR(area, 1e6, 1.0);
    EXPECT_EQ(split.outOfView, 0u);
    EXPECT_LT(pieces, 200000u);
}

// Looking along +y with a narrow view, what lies behind the camera is left out and what is ahead is kept.
TEST(LevelOfDetail, PiecesOutOfViewAreLeftOut) {
    const TriangleMesh plane = test::plane(200.0f);
    CameraFootprint camera = cameraAt({0, 0, 1.7}, 1.4e-3, 0.4);
    camera.forward = {0, 1, 0};
    const auto bands = lodBands(camera, 0.01, 0.05, 150.0, 16);
    const BandTargets split = splitTargetsByBand(plane, {}, camera, bands, 0.01);
    EXPECT_GT(split.outOfView, 0u);
    double area = 0.0, behind = 0.0;
    for (const TriangleMesh &mesh : split.meshes)
        for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
            area += mesh.area(t);
            const double y = (mesh.vertex(t, 0).y + mesh.vertex(t, 1).y + mesh.vertex(t, 2).y) / 3.0;
            if (y < -5.0) behind += mesh.area(t);
        }
    // The view's wedge (0.8 rad of 2 pi) of the half plane ahead, with the pieces along its edges.
    EXPECT_LT(area, 0.5 * 4e4);
    EXPECT_GT(area, 0.8 / (2.0 * 3.14159) * 4e4 * 0.5);
    EXPECT_EQ(behind, 0.0);
}

// Vertex weights are interpolated along the splits.
TEST(LevelOfDetail, WeightsFollowTheSplit) {
    const TriangleMesh plane = test::plane(100.0f);
    const std::vector<float> weights = {0.0f, 1.0f, 1.0f, 0.0f};  // x = -50: 0, x = +50: 1
    const CameraFootprint camera = cameraAt({0, 0, 1.7}, 1.4e-3);
    const auto bands = lodBands(camera, 0.01, 0.05, 80.0, 16);
    const BandTargets split = splitTargetsByBand(plane, weights, camera, bands, 0.01);
    for (std::size_t k = 0; k < bands.size(); ++k)
        for (std::size_t v = 0; v < split.meshes[k].positions.size(); ++v)
            EXPECT_NEAR(split.weights[k][v], (split.meshes[k].positions[v].x + 50.0f) / 100.0f, 1e-4);
}

}  // namespace firn
