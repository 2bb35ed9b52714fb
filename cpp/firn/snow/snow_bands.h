#pragma once

#include <cstddef>
#include <vector>

#include "firn/geometry/mesh.h"
#include "firn/geometry/orientation.h"
#include "firn/snow/level_of_detail.h"
#include "firn/snow/metaball_layout.h"
#include "firn/snow/snow_layer.h"
#include "firn/snow/snow_rasterizer.h"
#include "firn/util/progress.h"

namespace firn {

// One level of detail of a snow layer: the snow in its band of distances, on its own grids.
struct SnowBand {
    LodBand band;
    SnowGrids grids;           // density clipped to the band; the level set a few voxels beyond (its normals)
    std::size_t siteCount = 0; // landing sites on the band's targets
};

struct SnowBands {
    std::vector<SnowBand> bands;      // finest first; bands without snow left out
    std::vector<Metaball> metaballs;  // every band's, placed once
    std::size_t outOfView = 0;        // target pieces left out (nothing of them can show)
    Reorientation openSurfaces;
};

// Add Snow Layer with levels of detail by distance to `camera`: voxels as fine as settings.effectiveVoxelSize()
// near it, doubling with distance as a pixel's footprint doubles (level_of_detail.h), site spacing with them.
// Landing sites, sheltering, metaball layout and compaction are computed once for all bands; each band
// rasterizes every ball that reaches its distances at its voxel size, so two bands describe the same snow where
// they meet (within the coarser voxel). Budgets (voxels over all bands, sites) are checked before the work that
// grows with them; a lower bound first, in milliseconds.
SnowBands generateSnowBands(const TriangleMesh &targets, const TriangleMesh &occluders,
                            const SnowLayerSettings &settings, const CameraFootprint &camera, Progress *progress,
                            const std::vector<float> &depthWeights = {});

}  // namespace firn
