#pragma once

// Ray queries against ice grains (spheres) through Embree sphere points (RTC_GEOMETRY_TYPE_SPHERE_POINT).
// Embree works in float: it finds which grain a ray meets; the distance and the normal are then solved again in
// double precision against that grain's exact sphere, so grains of 0.1 mm keep their shape metres from the origin.
#include <cstddef>
#include <limits>
#include <memory>
#include <optional>

#include <glm/vec3.hpp>

#include "firn/grains/grain_set.h"

namespace firn {

class SphereScene {
  public:
    struct Hit {
        double distance;     // m along the unit ray direction, to where the ray enters the grain
        unsigned grain;      // index into the grain set
        glm::dvec3 normal;   // unit outward normal of the grain at the entry point
    };

    // A BVH over the first `count` grains (all by default). The grain set must outlive the scene.
    explicit SphereScene(const GrainSet &grains, std::size_t count = std::numeric_limits<std::size_t>::max());
    ~SphereScene();
    SphereScene(const SphereScene &) = delete;
    SphereScene &operator=(const SphereScene &) = delete;

    // The first grain the ray enters at distance in (0, tFar] (m, unit direction). Grains the origin lies in or
    // on (the grain a path is leaving, or one it overlaps within accumulation's tolerance) are passed through,
    // as is `ignoreGrain` (the grain a path just left or reflected from).
    std::optional<Hit> intersect(const glm::dvec3 &origin, const glm::dvec3 &direction,
                                 double tFar = std::numeric_limits<double>::infinity(),
                                 long ignoreGrain = -1) const;

    std::size_t size() const { return count_; }

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    const GrainSet &grains_;
    std::size_t count_;
};

// Distance (m) along a unit ray to where it enters the sphere (centre, radius), if it does at t > 0 from outside.
std::optional<double> raySphereEntry(const glm::dvec3 &origin, const glm::dvec3 &direction, const glm::dvec3 &centre,
                                     double radius);

}  // namespace firn
