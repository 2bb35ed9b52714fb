#include "firn/spray/emitter.h"

#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include "firn/util/error.h"

namespace firn {

double EmitterRectangle::area() const { return 4.0 * glm::length(glm::cross(halfU, halfV)); }

std::array<glm::dvec3, 4> EmitterRectangle::corners() const {
    return {pointAt(-1, -1), pointAt(1, -1), pointAt(1, 1), pointAt(-1, 1)};
}

EmitterRectangle emitterBetween(const Emitter &e, std::size_t frame, double t) {
    const EmitterRectangle &a = e.frames[frame], &b = e.frames[frame + 1];
    // Linear in every point: the centre and the half sides move linearly.
    return {a.centre + t * (b.centre - a.centre), a.halfU + t * (b.halfU - a.halfU),
            a.halfV + t * (b.halfV - a.halfV)};
}

void validate(const Emitter &e, std::size_t index, std::size_t frameCount) {
    const std::string name = "emitter " + std::to_string(index);
    if (e.frames.size() != frameCount)
        throw InvalidArgument(name + " has " + std::to_string(e.frames.size()) + " rectangles for " +
                              std::to_string(frameCount) + " frames");
    for (std::size_t f = 0; f < e.frames.size(); ++f) {
        const EmitterRectangle &r = e.frames[f];
        const glm::dvec3 sum = r.centre + r.halfU + r.halfV;
        if (!std::isfinite(sum.x + sum.y + sum.z))
            throw InvalidArgument(name + " has a non-finite coordinate at frame " + std::to_string(f));
        if (!(r.area() > 1e-8))
            throw InvalidArgument(name + " has no area at frame " + std::to_string(f) +
                                  " (its half sides are parallel or zero)");
    }
}

}  // namespace firn
