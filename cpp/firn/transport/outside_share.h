#pragma once

#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/scene.h"
#include "firn/util/random.h"

namespace firn {

// The share of voxel c's integral of sigma_t outside the closed occluders: photons never collide inside one, and
// the gathering skips its points there (sourceIn: the voxel's source is that of its part outside, what cameras
// see), so light tracing divides a voxel's photon sums by its integral outside. `tracer` answers which side a
// point lies on (PhotonTracer::enclosed), `rng` jitters the points in cubes a closed triangle cuts. Where it
// jitters, the share is a ratio of two unbiased sums: consistent, not unbiased.
double outsideShare(const Medium &medium, Medium::Accessor &density, const Occluders &occluders,
                    const PhotonTracer &tracer, const openvdb::Coord &c, Rng &rng);

}  // namespace firn
