#pragma once

#include <array>
#include <optional>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/source_lobe.h"

namespace firn {

// The source function of a traced voxel (docs/bake.md, Method 3) as the grids' two lobes, from its Monte Carlo
// estimate (MonteCarloReference::sourceIn, light_tracing.h).

// Fitted to the estimate's first four Legendre moments about the direct beams' axis (Prony's method).
Source tracedSourceByMoments(const SourceEstimate &S, double g);

// Where the fit by direction replaces the moments' lobes: snow scattering sharply forwards (g >= 0.8; at g 0.7
// the moments' pair holds the source: ball_rgb's views as main's, its blocks noisier), voxels of at most
// kMaxDirectionFitTau (in thicker ones a camera sees the first optical depth, not the voxel's mean: spray_dense's
// bias -2.8 -> -11.0 % fitted by direction), and a beam to give the peak its axis.
constexpr double kMinDirectionFitG = 0.8, kMaxDirectionFitTau = 2.0;
inline bool fittedByDirection(double g, double voxelTau) {
    return g >= kMinDirectionFitG && voxelTau <= kMaxDirectionFitTau;
}
// The optical depth of `voxel` of `medium` across, from the density at its centre.
inline double voxelOpticalDepth(const Medium &medium, Medium::Accessor &density, const openvdb::Coord &voxel) {
    return medium.voxelSize() * medium.optics().extinctionPerDensity * density.getValue(voxel);
}
inline bool fittedByDirection(const Medium &medium, Medium::Accessor &density, const openvdb::Coord &voxel) {
    return fittedByDirection(medium.optics().g, voxelOpticalDepth(medium, density, voxel));
}
// Where the points gathering a voxel's source are drawn where cameras see it (MonteCarloReference::sourceIn,
// `visible`; VisiblePoints), its lobes still fitted to the moments: the voxels the fit by direction leaves,
// thicker than kMaxDirectionFitTau, of forward scattering snow (measured on spray_dense's lumps, g 0.85).
inline bool gatheredWhereSeen(const Medium &medium, Medium::Accessor &density, const openvdb::Coord &voxel) {
    return medium.optics().g >= kMinDirectionFitG && voxelOpticalDepth(medium, density, voxel) > kMaxDirectionFitTau;
}

// Per direction of sourceDirections: the weight a fit gives it (visibilityFrom).
using DirectionWeights = std::array<double, kSourceDirections>;

// The source of a thin voxel of forward scattering snow (kMinDirectionFitG) as the grids' two lobes fitted to
// the source gathered in `directions` (fitByDirection; bench/bake_suite.py, over 2 seeds: slab_thin_forward
// 18.6 -> 10.2 %, per view +8, +20, +9, +23, -13 % -> -3, +5, +1, +16, -6 %), or to its moments where no beam
// reaches it or no fit holds.
Source tracedSourceByDirection(const SourceEstimate &S, const SourceDirections &directions,
                               const DirectionWeights &visibility, double g);

// The two lobes fitted to the exact source S.toward gathered in `directions` (grey): the peaked lobe about the
// beams' axis m (unit), k from 0.5 to min(g, kMaxLobeAnisotropy) by steps of 0.01 (or none), the fits at each k
// averaged by their likelihood (the best one where the estimate is exact); the broad lobe's linear form
// l0 + l1 . w. Weighted least squares in relative error against `moments` (the lobes fitted to the moments:
// weights that do not depend on the directional estimates, as their own values would, which favour those drawn
// low), each direction weighted by `visibility` too. The channels in the ratio of the estimate's means. None
// where the estimate holds no light or no fit is finite.
std::optional<Source> fitByDirection(const SourceEstimate &S, const SourceDirections &directions,
                                     const DirectionWeights &visibility, const glm::dvec3 &m, double g,
                                     const Source &moments);

// exp(-tau) from half a voxel out of the voxel's centre along each direction to the snow's bounds (up to tau
// 10): a thin layer's source is brightest along the layer (its limb), which no lobe pair holds and no camera
// sees but through the layer; weighted so, the fit keeps what cameras see, not the mean.
DirectionWeights visibilityFrom(const Medium &medium, Medium::ColumnMarcher &marcher, const openvdb::Coord &voxel,
                                const SourceDirections &directions);

// Caps a broad lobe's first moments at |l1| <= l0 (k <= 1/3: measured against the exact moments, k <= g, when
// one lobe held all: the thin g = 0.85 ball 16 % against 26 %).
void capBroad(BroadLobe &S);

}  // namespace firn
