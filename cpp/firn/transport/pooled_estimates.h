#pragma once

#include <vector>

#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/monte_carlo.h"

namespace firn {

// Light-traced voxels' scattered light (docs/bake.md, Method 3) with the source towards each direction of the fit
// by direction (SourceEstimate::toward) pooled over a flat uniform layer: where at least kMinPooledNeighbours of a
// voxel's 26 neighbours are traced, of nearly its density (within kPooledDensityRatio; a flat face of uniform
// snow has 17) and fitted by direction (fittedByDirection: only those hold a `toward`), `toward` is the sum over the voxel and those neighbours scaled to the voxel's own mean l0 (its
// amount, moments and beams its own). Measured, not derived: on slab_thin_forward (three layers of optical depth 1,
// g 0.87) every view moves towards the core's Monte Carlo, mean error per block 10.1 -> 7.5 % over 2 seeds, and
// 9.4 -> 7.0 % at 16 times the photons, the render's spread across seeds 3.5 -> 3.4 %: a change of the fit's bias,
// not of its noise. Pooling more (l0, the moments, voxels at edges, fewer neighbours, neighbours of other density)
// biased curved pieces (ball_forward -2.7 -> -12 %) and pooled nothing worth it anywhere (docs/benchmarks.md, pooled).
constexpr double kPooledDensityRatio = 1.1;
constexpr int kMinPooledNeighbours = 17;
// `index`: voxel -> its place in `voxels` and `estimates`, -1 elsewhere.
std::vector<SourceEstimate> pooledEstimates(const Medium &medium, const openvdb::Int32Tree &index,
                                            const std::vector<openvdb::Coord> &voxels,
                                            const std::vector<SourceEstimate> &estimates);

}  // namespace firn
