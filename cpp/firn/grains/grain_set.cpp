#include "firn/grains/grain_set.h"

#include <cmath>
#include <string>

#include "firn/util/error.h"

namespace firn {

void validate(const GrainSet &grains) {
    if (grains.centres.size() != grains.radii.size())
        throw InvalidArgument("grain centres (" + std::to_string(grains.centres.size()) + ") and radii (" +
                              std::to_string(grains.radii.size()) + ") differ in number");
    for (std::size_t i = 0; i < grains.size(); ++i) {
        const glm::dvec3 &c = grains.centres[i];
        if (!(std::abs(c.x) <= kMaxGrainCoordinate && std::abs(c.y) <= kMaxGrainCoordinate && std::abs(c.z) <= kMaxGrainCoordinate))
            throw InvalidArgument("grain " + std::to_string(i) + " has a centre that is not finite or lies beyond 1e6 m");
        if (!(grains.radii[i] > 0.0 && grains.radii[i] <= kMaxGrainRadius))
            throw InvalidArgument("grain " + std::to_string(i) + " has a radius that is not a length in (0, 1000] m");
    }
}

}  // namespace firn
