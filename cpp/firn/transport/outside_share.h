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
// Limit: a voxel no closed triangle cuts is taken to lie wholly on its centre's side, and a cube one triangle's plane
// splits to lie on its two farthest corners' sides (remembered per triangle): both assume the closed triangles alone
// bound the enclosed region. The enclosed test asks the first triangle straight up and down, open ones too, so its
// answer also changes across an open triangle inside a closed body (an open ground through a box) and, where closed
// meshes overlap (a ski buried in the snow's surface mesh: under the ski, the ray up meets its underside and reads
// outside), across the vertical walls under and over their rims; a voxel cut by those alone reads 0 or 1.
double outsideShare(const Medium &medium, Medium::Accessor &density, const Occluders &occluders,
                    const PhotonTracer &tracer, const openvdb::Coord &c, Rng &rng);

}  // namespace firn
