#pragma once

#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"

namespace firn {

// The camera that decides how much detail snow needs: where it is, where it looks, and the angle one pixel
// spans. Snow d m away is seen at d x pixelAngle m per pixel; finer voxels there cost memory and time and show
// nothing.
struct CameraFootprint {
    glm::dvec3 position{0.0};            // m
    glm::dvec3 forward{0.0, 1.0, 0.0};   // unit, the view direction
    double pixelAngle = 1e-3;            // rad per pixel: the field of view over the pixels across it
    double viewHalfAngle = 3.2;          // rad, a cone around `forward` holding the whole view (>= pi: all around)

    double footprint(double distance) const { return distance * pixelAngle; }  // m per pixel
    // Whether a sphere (centre, radius m) may hold anything in view.
    bool mayView(const glm::dvec3 &centre, double radius) const;
    // Throws InvalidArgument naming the first field out of range.
    void validate() const;
};

// Voxel size (m) for snow `distance` m from the camera: fineVoxel x 2^k, the coarsest such size not coarser
// than a pixel's footprint there (fineVoxel itself where the footprint is finer), and never past
// fineVoxel x 2^(bands - 1).
int lodLevel(double distance, const CameraFootprint &camera, double fineVoxel, int bands);
double lodVoxelSize(int level, double fineVoxel);

// One level of detail: the snow between two distances from the camera, at one voxel size.
struct LodBand {
    int level = 0;
    double voxelSize = 0.0;  // m
    double spacing = 0.0;    // m between landing sites: the user's, scaled with the voxel size
    double nearDistance = 0.0, farDistance = 0.0;  // m from the camera, [near, far); far is infinite for the last
};

// Bands of doubling voxel sizes from fineVoxel, enough to reach `farthest` m, at most maxBands. Spacing grows
// with the voxel (balls keep as many voxels across them), never below `spacing`.
std::vector<LodBand> lodBands(const CameraFootprint &camera, double fineVoxel, double spacing, double farthest,
                              int maxBands);

// Target triangles split so that each lies within one band (or is small against its band's spacing), sorted
// into one mesh per band by their nearest point to the camera (the finer side: never coarser than a pixel).
// Triangles out of view are left out. Vertex weights (empty, or one per target vertex) follow the split.
struct BandTargets {
    std::vector<TriangleMesh> meshes;          // one per band
    std::vector<std::vector<float>> weights;   // per band: empty, or one per vertex of its mesh
    std::size_t outOfView = 0;                 // pieces left out
};
BandTargets splitTargetsByBand(const TriangleMesh &targets, const std::vector<float> &weights,
                               const CameraFootprint &camera, const std::vector<LodBand> &bands, double fineVoxel);

}  // namespace firn
