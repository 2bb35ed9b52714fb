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
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
            throw InvalidArgument("grain " + std::to_string(i) + " has a non-finite centre");
        if (!(grains.radii[i] > 0.0) || !std::isfinite(grains.radii[i]))
            throw InvalidArgument("grain " + std::to_string(i) + " has a radius that is not a positive length (m)");
    }
}

}  // namespace firn
