#pragma once

#include <glm/vec3.hpp>

namespace firn {

// A linear Rec.709 RGB triple (the primaries Cycles renders in): radiance, albedo or irradiance per channel.
using Rgb = glm::dvec3;

// The three channels' mean (grey), summed in the vector's own precision.
template <class T, glm::qualifier Q>
double channelMean(const glm::vec<3, T, Q> &c) {
    return (c.x + c.y + c.z) / 3.0;
}

}  // namespace firn
