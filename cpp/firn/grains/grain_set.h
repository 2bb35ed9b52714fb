#pragma once

// Ice grains as spheres: what accumulation makes and the grain renderer reads.
#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

namespace firn {

inline constexpr double kIceRefractiveIndex = 1.31;  // real index of ice in the visible (Warren & Brandt 2008)
inline constexpr double kMaxGrainRadius = 1e3;       // m: anything larger is a mistake in units
inline constexpr double kMaxGrainCoordinate = 1e6;   // m: beyond it Embree's float coordinates lose the grains

struct GrainSet {
    std::vector<glm::dvec3> centres;  // m, world space
    std::vector<double> radii;        // m

    std::size_t size() const { return radii.size(); }
    bool empty() const { return radii.empty(); }
    void add(const glm::dvec3 &centre, double radius) {
        centres.push_back(centre);
        radii.push_back(radius);
    }
};

// InvalidArgument unless centres and radii have the same length, centres lie within kMaxGrainCoordinate and
// radii in (0, kMaxGrainRadius].
void validate(const GrainSet &grains);

}  // namespace firn
