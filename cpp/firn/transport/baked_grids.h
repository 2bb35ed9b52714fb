#pragma once

#include <array>
#include <string>

#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/scene.h"
#include "firn/util/color.h"

namespace firn {

// The bake's output, written beside `density` in the snow's VDB (contract: docs/vdb-contract.md).
// The snow's source function S, the radiance it scatters towards w per unit extinction (W/m^2/sr, RGB), per
// channel one Henyey-Greenstein lobe of mean l0 = source and first moment 4 pi l1 / 3, l1 = (source_x,
// source_y, source_z) (lobeRadiance, source_lobe.h), w the world direction towards the viewer (Cycles'
// Geometry > Incoming). Rendered with absorption sigma_t = k density and emission sigma_t S(w), it gives the
// snow's scattered radiance.
struct BakedGrids {
    static constexpr std::array<const char *, 4> kNames{"firn_source", "firn_source_x", "firn_source_y",
                                                        "firn_source_z"};
    std::array<openvdb::Vec3fGrid::Ptr, 4> source;  // in kNames' order

    openvdb::GridPtrVec grids() const;
    // Picks the four grids out of a file's grids by name. Throws InvalidArgument if one is missing.
    static BakedGrids find(const openvdb::GridPtrVec &grids);
};

// The source grids at `factor` (>= 1) times the density's voxel size: a coarse voxel holds the extinction-
// weighted mean of its factor^3 voxels where there is snow, elsewhere the mean of the values the bake extends
// beyond the snow, and a ring of zeros surrounds them (Cycles holds a Vec3 grid's edge value half a voxel
// further). Cycles stores a grid densely over its bounding box: a factor of 2 keeps 1/8 of the source's memory.
BakedGrids coarsened(const BakedGrids &fine, const openvdb::FloatGrid &density, int factor);

// Integrates the baked emission along rays, as the renderer does; one per thread.
class BakedRadiance {
  public:
    BakedRadiance(const Scene &scene, const BakedGrids &baked);
    // Radiance the baked snow sends back along the ray (towards its origin) from t = 0 to tMax (m),
    // integrated in steps of at most `step` voxels with the exact exponential of each step.
    Rgb along(const Ray &ray, double tMax, double step);

  private:
    using Reader = openvdb::tree::ValueAccessor<const openvdb::Vec3fTree>;
    const Scene &scene_;
    Medium::ColumnMarcher marcher_;
    Medium::Accessor density_;
    std::array<Reader, 4> source_;
    double sourceIndexPerDensityIndex_;  // the source grids may be coarser than the density
};

// What Cycles draws for the snow along a camera ray with the contract's material: the integral of
// sigma_t S(-direction) exp(-tau) along the ray, through the trilinear density and source grids, up to
// the first occluder (the sky and surfaces behind the snow are not included: the renderer adds them,
// attenuated by exp(-tau)).
Rgb renderBaked(const Scene &scene, const BakedGrids &baked, const Ray &ray);

}  // namespace firn
