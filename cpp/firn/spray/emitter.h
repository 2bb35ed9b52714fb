#pragma once

#include <array>
#include <vector>

#include <glm/vec3.hpp>

namespace firn {

// A rectangle that throws snow (a ski, a wheel's contact patch): centre + s halfU + t halfV, s, t in [-1, 1].
struct EmitterRectangle {
    glm::dvec3 centre{0.0};  // m, world
    glm::dvec3 halfU{0.0};   // m: half the rectangle's first side
    glm::dvec3 halfV{0.0};   // m: half its second side (need not be orthogonal to halfU: a parallelogram)

    glm::dvec3 pointAt(double s, double t) const { return centre + s * halfU + t * halfV; }
    double area() const;  // m^2
    // The four corners, counter-clockwise around halfU x halfV.
    std::array<glm::dvec3, 4> corners() const;
};

// An emitter's rectangle at each frame of a sequence; between frames every point moves in a straight line at
// constant speed (corners interpolated linearly), which is what a sub-step sees.
struct Emitter {
    std::vector<EmitterRectangle> frames;
};

// The rectangle a fraction `t` (0..1) of the way from frame `frame` to frame `frame + 1`.
EmitterRectangle emitterBetween(const Emitter &emitter, std::size_t frame, double t);

// Throws InvalidArgument (naming emitter `index`) unless it has `frameCount` rectangles of finite coordinates and
// positive area.
void validate(const Emitter &emitter, std::size_t index, std::size_t frameCount);

}  // namespace firn
