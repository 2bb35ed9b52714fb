#pragma once

#include <vector>

#include <glm/vec3.hpp>

#include "firn/snow/snow_rasterizer.h"
#include "firn/spray/emitter.h"

namespace firn {

struct TrackSettings {
    double thickness = 0.02;        // m: the emitter's box reaches this far under its rectangle (a ski's sole)
    double compactionDepth = 0.05;  // m: the layer under a track that takes the snow pushed out of it
    double maxDensity = 917.0;      // kg/m^3 the compacted layer never exceeds (ice)

    void validate() const;
};

struct TrackStats {
    std::size_t carvedVoxels = 0;  // voxels whose level set or density the track changed
    double removedMass = 0.0;      // kg taken out of the swept volume
    double compactedMass = 0.0;    // kg added to the layer below (less than removed where it reached maxDensity)
};

// Cuts what the rectangles (an emitter's positions during one frame, in order) sweep out of the snow: at each
// position, the box from `thickness` under the rectangle (along its normal facing up, away from `down`) up to
// above the snow over it (and beside it, within the compaction layer's reach); consecutive boxes overlap
// (positions are added between those given when the rectangle moves more than half the box's narrowest side).
// The surface level set becomes the difference snow - swept (max(phi, -phi_swept), voxel by voxel); the density
// in the swept volume is removed (voxels on its surface keep their uncovered part, the one-voxel ramp of the snow
// layer) and its mass spread evenly over the snow voxels within compactionDepth below the track (where the nearest
// swept point is straight above), so mass is conserved up to maxDensity. Returns what changed; carvedVoxels = 0
// leaves the grids untouched. Throws BudgetExceeded, before allocating, when the swept volume's grid could hold more
// than maxVoxels voxels.
TrackStats carveTrack(SnowGrids &snow, const std::vector<EmitterRectangle> &positions, const glm::dvec3 &down,
                      const TrackSettings &settings, double maxVoxels);

}  // namespace firn
