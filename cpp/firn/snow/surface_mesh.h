#pragma once

#include <cstddef>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/util/progress.h"

namespace firn {

// The snow's surface as a triangle mesh: the zero crossing of its `surface` level set, meshed with OpenVDB's
// volume-to-mesh (tools/VolumeToMesh.h). The viewport proxy and stacked snow layers use it.

struct SurfaceMeshSettings {
    double adaptivity = 0.0;       // 0..1: OpenVDB's merging of flat regions into larger polygons (0: none)
    std::size_t maxTriangles = 0;  // triangle budget; 0: none. Otherwise at least kMinTriangleBudget
    double isovalue = 0.0;         // m: the level set's value meshed; 0 is the surface, > 0 outside it (within
                                   // the narrow band: at most 2 voxels)
};

// Below this a budget cannot hold even a coarse closed surface of a snow layer.
constexpr std::size_t kMinTriangleBudget = 100;

struct SurfaceMesh {
    std::vector<openvdb::Vec3s> vertices;   // world space of the grid (m)
    std::vector<openvdb::Vec3I> triangles;  // counter-clockwise seen from outside (quads split)
    double adaptivity = 0.0;                // the adaptivity the mesh was made with
    double voxelSize = 0.0;                 // m, of the level set meshed (coarser than the grid's within a budget)
};

// Meshes the level set's crossing of the settings' isovalue (0: the surface) with OpenVDB's volume-to-mesh at the settings' adaptivity. Within a
// budget, large snow is meshed from the level set sampled on voxels 2, 4, 8... times coarser (its values are
// distances in m, so the zero crossing stays the same surface, to a coarse voxel), the factor guessed from the
// active voxels and raised until the mesh fits (without adaptivity the search counts triangles and meshes once);
// the result is the first that fits, or the smallest made (a budget too small for the snow's shape). Throws InvalidArgument for a grid that is not a level set with a
// uniform linear transform, or a budget below kMinTriangleBudget; Cancelled when `progress` is cancelled
// between attempts.
SurfaceMesh meshSurface(const openvdb::FloatGrid &surface, const SurfaceMeshSettings &settings,
                        const SubProgress &progress);

}  // namespace firn
