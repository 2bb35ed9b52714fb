#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <string>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include "firn/transport/medium.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/scene.h"
#include "firn/transport/source_lobe.h"
#include "firn/util/color.h"
#include "firn/util/progress.h"

namespace firn {

// The bake's output, written beside `density` in the snow's VDB (contract: docs/vdb-contract.md).
// The snow's source function S, the radiance it scatters towards w per unit extinction (W/m^2/sr, RGB), per
// channel two Henyey-Greenstein lobes: a broad one of mean l0 = source and first moment 4 pi l1 / 3, l1 =
// (source_x, source_y, source_z) (lobeRadiance, source_lobe.h), and a peaked one of mean p0 = source_peak and
// grey first moment p1 = source_peak_l1 (peakRadiance), w the world direction towards the viewer (Cycles'
// Geometry > Incoming). Rendered with absorption sigma_t = k density and emission sigma_t S(w), it gives the
// snow's scattered radiance.
struct BakedGrids {
    static constexpr std::array<const char *, 6> kNames{"firn_source",   "firn_source_x",    "firn_source_y",
                                                        "firn_source_z", "firn_source_peak", "firn_source_peak_l1"};
    static constexpr std::size_t kCount = kNames.size();
    using Values = std::array<openvdb::Vec3f, kCount>;  // the grids' values at a point, in kNames' order
    std::array<openvdb::Vec3fGrid::Ptr, kCount> source;  // in kNames' order
    // The density the renderer scatters itself rather than drawing S (kg/m^3: scatteredDensity), on kScatterScale
    // times the density's voxels; null where it scatters nowhere (no grid is written: Cycles' memory holds it
    // densely over its box, an eighth of it at the density's voxels' box).
    static constexpr const char *kScatterName = "firn_scatter";
    static constexpr double kScatterOpticalDepth = 2.0;  // sigma_t h under which traced snow scatters (thin-ring)
    static constexpr int kScatterScale = 2;              // density voxels per firn_scatter voxel along an axis
    openvdb::FloatGrid::Ptr scatter;
    // The density's voxels where the renderer scatters (scatterMask), in the density's transform; null with
    // `scatter`. Not written: a joint bake takes each object's own scattered density on them (bakedGridsOf).
    openvdb::BoolGrid::Ptr scattered;

    openvdb::GridPtrVec grids() const;  // the six, then the scatter grid where there is one
    // Whether a file's grid of this name is a bake's (replaced by a new bake, removed by Clear Bake).
    static bool isBaked(const std::string &name);
    // Picks the six grids, and the scatter grid if there is one, out of a file's grids by name. Throws
    // InvalidArgument if one of the six is missing.
    static BakedGrids find(const openvdb::GridPtrVec &grids);
};

// The source grids' trees (kNames' order) at `factor` (>= 2) times the density's voxel size: a coarse voxel holds
// the extinction-weighted mean of its factor^3 voxels where there is snow, elsewhere the mean of the values the
// bake extends beyond the snow (the fine voxels whose firn_source is not zero), and a ring of zeros surrounds them
// (Cycles holds a Vec3 grid's edge value half a voxel further). Cycles stores a grid densely over its bounding box:
// a factor of 2 keeps 1/8 of the source's memory. The grids' transform is the density's scaled by `factor`.
// Over the active voxels of `fineTopology`, the six values of a voxel read at once by the readers that newReader()
// makes (one per thread): a bake coarsens its grids without building them at the density's resolution first
// (each such tree took 52 bytes per active voxel of the car sample's memory peak), and reads each voxel once
// (a grid at a time, the car's grids took 1.9 processor seconds, 0.5 so).
using FineValuesReaders = std::function<std::function<BakedGrids::Values(const openvdb::Coord &)>()>;
std::array<openvdb::Vec3fTree::Ptr, BakedGrids::kCount> coarsenedSources(const openvdb::BoolTree &fineTopology,
                                                                         const FineValuesReaders &newReader,
                                                                         const openvdb::FloatTree &density, int factor,
                                                                         const SubProgress &progress);

// The baked source towards w (unit, towards the viewer) from the grids' values at a point: per channel the broad
// lobe plus the peaked one, W/m^2/sr per unit extinction.
Rgb bakedSourceToward(const BakedGrids::Values &source, const glm::dvec3 &w);

// Integrates the baked emission along a ray as the renderer does: the radiance the baked snow sends back along
// it (towards its origin) from t = 0 to tMax (m), in steps of at most `step` voxels with the exact exponential of
// each step. sourceAt(ijk) gives the grids' values (BakedGrids::Values) at a point of the density's index
// space: SourceGridsSampler, or the bake's own values before it writes its grids. `through`: the transmittance the
// snow leaves at tMax (what lies beyond is seen through it; under 1e-6 where the march stops early).
template <typename SourceAt>
Rgb bakedRadianceAlong(const Scene &scene, Medium::ColumnMarcher &marcher, SourceAt &sourceAt, const Ray &ray,
                       double tMax, double step, double *through = nullptr) {
    const double k = scene.medium->optics().extinctionPerDensity;
    const glm::dvec3 w = -ray.direction;  // towards the viewer
    Rgb radiance(0.0);
    double transmittance = 1.0;
    marcher.march(ray.origin, ray.direction, tMax, step, [&](const openvdb::Vec3d &ijk, double dt) {
        const double sigmaT = k * marcher.densityAt(ijk);
        if (sigmaT <= 0.0) return true;
        const Rgb S = bakedSourceToward(sourceAt(ijk), w);
        const double opacity = 1.0 - std::exp(-sigmaT * dt);
        radiance += transmittance * opacity * S;
        transmittance *= 1.0 - opacity;
        return transmittance > 1e-6;
    });
    if (through) *through = transmittance;
    return radiance;
}

// The source grids' values at a point, trilinear as the renderer reads them; one per thread.
class SourceGridsSampler {
  public:
    SourceGridsSampler(const Medium &medium, const BakedGrids &baked);
    BakedGrids::Values operator()(const openvdb::Vec3d &ijk);  // ijk: the density's index space

  private:
    using Reader = openvdb::tree::ValueAccessor<const openvdb::Vec3fTree>;
    std::array<Reader, BakedGrids::kCount> source_;
    double sourceIndexPerDensityIndex_;  // the source grids may be coarser than the density
};

// bakedRadianceAlong through BakedGrids; one per thread.
class BakedRadiance {
  public:
    BakedRadiance(const Scene &scene, const BakedGrids &baked);
    Rgb along(const Ray &ray, double tMax, double step) {
        return bakedRadianceAlong(scene_, marcher_, source_, ray, tMax, step);
    }

  private:
    const Scene &scene_;
    Medium::ColumnMarcher marcher_;
    SourceGridsSampler source_;
};

// What Cycles draws for the snow along a camera ray with the contract's material: the integral of
// sigma_t S(-direction) exp(-tau) along the ray, through the trilinear density and source grids, up to
// the first occluder (the sky and surfaces behind the snow are not included: the renderer adds them,
// attenuated by exp(-tau)).
Rgb renderBaked(const Scene &scene, const BakedGrids &baked, const Ray &ray);

// The voxels where the renderer scatters (benchmarks.md, thin-ring's rule B; the firn_scatter grid): on, the snow
// voxels of `candidates` of sigma_t h under `thinDepth`. The bake's candidates are the voxels it traces
// (bake::TracedSnow::voxels): there the renderer's own scattering beats the baked lobes, while a diffused surface's
// fringe would scatter again the light the surface model already put behind it.
openvdb::BoolTree::Ptr scatterMask(const Medium &medium, const std::vector<openvdb::Coord> &candidates,
                                   double thinDepth);
// The same for a scene not baked here (the benches): the candidates are the voxels its bake would trace, or every
// snow voxel unless `tracedOnly`.
openvdb::BoolTree::Ptr scatterMask(const Scene &scene, double thinDepth, bool tracedOnly);
// The firn_scatter grid's values: the density the renderer scatters itself (kg/m^3), on voxels `factor` times the
// density's (BakedGrids::kScatterScale). Coarse voxel J lies where density voxel factor J does and holds the largest
// density of the `scattered` voxels within `factor` of it along each axis (|c - factor J| <= factor): every density
// voxel of a coarse cell lies in the hats of all its corners, so the trilinear read is at least the density
// throughout snow that scatters whole, and beside snow that does not (a diffused surface behind its thin fringe) no
// more than the scattered voxels' own density. The renderer scatters scatteredShare of the extinction.
openvdb::FloatTree::Ptr scatteredDensity(const openvdb::BoolTree &scattered, const openvdb::FloatTree &density,
                                         int factor);
// The share of the extinction the renderer scatters at a point of trilinear `density` where firn_scatter reads
// `scatteredDensity` (both kg/m^3): min(density, scattered) / density, 0 in air. A share read trilinearly instead
// (before lead-95) scattered half a share of the carrier behind a diffused surface's fringe: the renderer scattered
// light the carrier already sends, a flat top under a partly filled voxel of omega 0.98 +39 % (now +13 %).
double scatteredShare(double density, double scatteredDensity);

// The render of MixedRender (monte_carlo.h): the renderer scatters, all orders, the density of the snow of optical
// depth per voxel sigma_t h under `thinDepth` and draws the baked emission of the rest (scatteredShare), the
// scattered density read trilinearly from voxels `shareScale` times the density's (scatteredDensity; the bake's
// firn_scatter: BakedGrids::kScatterScale). `samples` paths per ray; (mean, standard error) per ray as
// MonteCarloReference's.
std::vector<RadianceEstimate> renderScatteringWhereThin(const MonteCarloReference &reference, const BakedGrids &baked,
                                                        const std::vector<Ray> &rays, int samples, std::uint64_t seed,
                                                        double thinDepth, int bounces, bool tracedOnly,
                                                        int shareScale = BakedGrids::kScatterScale);

}  // namespace firn
