#pragma once

// The snow's level set at world points, as the spray reads it (emission, flight, the lumps resting on it).

#include <cmath>
#include <limits>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

namespace firn {

// Index coordinates (voxels) past which no snow lies: no grid a budget admits reaches 2^30 voxels from its origin,
// and OpenVDB's samplers floor a point into an int that such coordinates overflow (undefined behaviour: an emitter
// moved 1e30 m in a frame, tests/fuzz spray seed 42).
constexpr double kMaxSnowIndex = 1073741824.0;

// Trilinear over a level set's tree (its reads are thread-safe; an accessor-based GridSampler is quicker per thread).
using SnowSampler = openvdb::tools::GridSampler<openvdb::FloatTree, openvdb::tools::BoxSampler>;

// The level set (m) through `phi` (an OpenVDB GridSampler) at world point p; +infinity (outside the snow) past
// kMaxSnowIndex or at a point that is not finite.
template <typename Sampler>
double snowLevelSetAt(const Sampler &phi, const glm::dvec3 &p) {
    const openvdb::Vec3d ijk = phi.transform().worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
    if (!(std::abs(ijk.x()) < kMaxSnowIndex && std::abs(ijk.y()) < kMaxSnowIndex && std::abs(ijk.z()) < kMaxSnowIndex))
        return std::numeric_limits<double>::infinity();
    return double(phi.isSample(ijk));
}

}  // namespace firn
