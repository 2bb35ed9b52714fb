#pragma once

#include <glm/vec3.hpp>

namespace firn {

// A linear Rec.709 RGB triple (the primaries Cycles renders in): radiance, albedo or irradiance per channel.
using Rgb = glm::dvec3;

}  // namespace firn
