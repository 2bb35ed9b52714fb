#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"
#include "firn/geometry/orientation.h"
#include "firn/geometry/ray_caster.h"
#include "firn/snow/metaball_layout.h"
#include "firn/snow/snow_rasterizer.h"
#include "firn/snow/snowfall.h"
#include "firn/util/progress.h"

namespace firn {

// Everything Add Snow Layer asks for. Angles in radians, lengths in metres, densities in kg/m^3.
struct SnowLayerSettings {
    double depth = 0.1;        // m of snow on open level ground
    double maxSlope = 1.047;   // rad from horizontal (60 deg)
    double spacing = 0.05;     // m between landing sites: small is smooth, large is uneven
    double randomness = 0.25;  // 0..1
    double smoothness = 0.5;   // 0..1
    glm::vec3 direction{0.0f, 0.0f, -1.0f};  // the way snow falls
    double spread = 0.26;      // rad, half-angle of the snowfall cone (15 deg)
    int exposureRays = 16;
    double densityTop = 120.0;     // kg/m^3
    double densityBottom = 350.0;  // kg/m^3
    double compaction = 0.5;       // 0..1
    double voxelSize = 0.0;        // m; 0 picks it from the depth and spacing
    double maxVoxels = 50e6;
    std::uint64_t seed = 0;

    // Throws InvalidArgument naming the first setting out of range.
    void validate() const;
    // The voxel size used: the override, or enough voxels through the depth and across a ball.
    double effectiveVoxelSize() const;

    SnowfallSettings snowfall() const;
    MetaballLayoutSettings layout() const;
    RasterSettings raster() const;
};

struct SnowLayer {
    std::vector<Metaball> metaballs;  // kept, so edited balls can be rasterized again
    SnowGrids grids;
    std::size_t siteCount = 0;
    double voxelSize = 0.0;           // m
    Reorientation openSurfaces;       // open target surfaces turned to face up (their normals ignored)
};

// Add Snow Layer's whole computation: landing sites on `targets`, sheltered by `occluders` and by the
// targets themselves; metaball columns; the density and surface grids. Open target surfaces take snow on their
// upper side whatever their winding (orientOpenSurfaces); closed ones keep their normals. Checks the voxel budget before
// allocating. Reports to and can be cancelled through `progress` (may be null). `depthWeights` (empty, or 0..1
// per target vertex) scales the depth where snow lands (a vertex group mask: findLandingSites).
SnowLayer generateSnowLayer(const TriangleMesh &targets, const TriangleMesh &occluders,
                            const SnowLayerSettings &settings, Progress *progress,
                            const std::vector<float> &depthWeights = {});

// The targets with their open surfaces turned to face `up` (orientOpenSurfaces), and the shelter: a RayCaster over
// them and the occluders.
struct ShelteredTargets {
    const TriangleMesh *targets = nullptr;  // as given: they outlive this
    TriangleMesh turned;                      // a copy of them, oriented, only when some triangle turned
    Reorientation openSurfaces;
    std::unique_ptr<const RayCaster> shelter;

    const TriangleMesh &oriented() const { return openSurfaces.triangles > 0 ? turned : *targets; }
};

// The shelter is built from the targets as given while the triangles to turn are found beside it (orientation's
// weld is serial: it takes the other core); most scenes turn no triangle and need no oriented copy of a million
// triangles (18 MB of fresh memory); when one turned the targets are copied, turned and the shelter built again.
// Without occluders the shelter is built on the targets in place (no joined copy): they outlive it.
ShelteredTargets shelterTargets(const TriangleMesh &targets, const TriangleMesh &occluders, const glm::vec3 &up);

// The smallest depth weight (1 for none, or for weights out of 0..1: findLandingSites refuses those): the
// lower bound of snow_volume_bound.h times it stays a lower bound.
double leastDepthWeight(const std::vector<float> &depthWeights);

// Throws InvalidArgument, saying why snow may not land, when there are no balls.
void requireLandedSnow(const std::vector<Metaball> &balls);

// Mean density (kg/m^3) of the voxels wholly inside the snow; 0 for no snow.
double meanInteriorDensity(const SnowGrids &grids);

}  // namespace firn
