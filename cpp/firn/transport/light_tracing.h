#pragma once

#include <cstdint>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/transport/monte_carlo.h"
#include "firn/transport/scene.h"
#include "firn/util/progress.h"

namespace firn {

// Light tracing (docs/bake.md Method 3): the source function of many voxels from paths that serve every voxel
// they cross, for clouds of thrown snow too large to gather per voxel. Photons enter a box just inside the medium's
// bounds through its faces: the suns' beams (their direction jittered over the disc) where no occluder hides the sun,
// and all other light arriving there (sky, occluders' reflections, light the medium sent out and the scene
// returned), one path of the reference traced outwards per photon for its radiance. Inside, the reference's own
// tracking (PhotonTracer::follow): delta tracking, Henyey-Greenstein, Lambertian occluders, roulette,
// until the photon leaves the box; none starts inside a closed occluder (no light reaches there). Each real
// collision in a voxel adds the power arriving and its direction to the voxel's sums (the collision estimator of
// the integral of sigma_t phi and of the moments; divided by the voxel's integral of sigma_t outside closed
// occluders, as the gathering's points skip their inside: the extinction-weighted mean sourceIn gives), except a
// sun beam's first collision: that single scattering is each voxel's sourceIn beams (noise-free peaked lobe).
// Photon i draws from its own stream and the sums are reduced in fixed chunks in order: the same grids on any
// thread count.
struct LightTracingPlan {
    long photons = 0;     // 0: too costly, or lamps in the scene (planLightTracing): leave the voxels to others
    int beamSamples = 0;  // points per voxel for the direct beams
    std::size_t sumsBytes = 0;  // the voxels' sums photons add to (ArrivingLight; ArrivingToward where fitted by direction)
};

// The photons and beam points that `share` of `maxSteps` tracking steps buy, measured on a pilot of both; none where
// fewer photons than `share` of the least (kMinPhotons), or than kMinPhotonsPerVoxel, are affordable. A share under
// 1 scales the plan down for a preview (BakeQuality::Draft): photons and floor alike, where the per-voxel floor
// (the lobes' bias) stays.
LightTracingPlan planLightTracing(const MonteCarloReference &reference, const std::vector<openvdb::Coord> &voxels,
                                  double maxSteps, std::uint64_t seed, double share = 1.0);

// The source estimates of `voxels` (as sourceIn's), by light tracing.
std::vector<SourceEstimate> lightTracedSources(const MonteCarloReference &reference,
                                               const std::vector<openvdb::Coord> &voxels,
                                               const LightTracingPlan &plan, std::uint64_t seed,
                                               const SubProgress &progress);

}  // namespace firn
