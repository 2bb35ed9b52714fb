#pragma once

#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"

namespace firn {

// Ray queries against world-space triangles, through Embree. Built once, then const and safe to query
// from any number of threads (TBB loops).
class RayCaster {
  public:
    struct Hit {
        float distance;       // m along the (normalized) ray direction
        unsigned triangle;    // index into the mesh's triangles
        glm::vec3 normal;     // unit geometric normal, counter-clockwise winding
    };

    // How many rays the caster will answer, which picks its BVH: `Few` (about as many as it has triangles: a
    // snow layer's shelter) a Morton build, the fastest to make; `Many` (millions over a small mesh: the bake's
    // occluders) a SAH build, slower to make and about twice as fast to query.
    enum class Rays { Few, Many };

    explicit RayCaster(TriangleMesh mesh, Rays rays = Rays::Few);  // kept (moved in: pass a temporary to spare a copy)
    // Built on `mesh` in place, not copied (a million triangles: 18 MB): `mesh` must outlive the caster, unchanged
    // and at its address.
    static std::unique_ptr<const RayCaster> over(const TriangleMesh &mesh, Rays rays = Rays::Few);
    ~RayCaster();
    RayCaster(const RayCaster &) = delete;
    RayCaster &operator=(const RayCaster &) = delete;

    // True if anything lies on the segment origin + t * direction, t in [tNear, tFar] (m, direction normalized).
    bool occluded(const glm::vec3 &origin, const glm::vec3 &direction, float tNear = 0.0f,
                  float tFar = std::numeric_limits<float>::infinity()) const;

    std::optional<Hit> intersect(const glm::vec3 &origin, const glm::vec3 &direction, float tNear = 0.0f,
                                 float tFar = std::numeric_limits<float>::infinity()) const;

    // Distance (m) from `point` to the nearest triangle, if one lies within `maxDistance` (m); an Embree
    // point query (BVH-culled), the closest point on each candidate triangle computed in double precision.
    std::optional<double> closestDistance(const glm::dvec3 &point, double maxDistance) const;

    // The triangles sharing a point with the axis-aligned box [lo, hi] (m), ascending: an Embree point query about
    // its centre reaching its corners (BVH-culled), each candidate tested exactly (triangleOverlapsBox).
    std::vector<unsigned> trianglesInBox(const glm::dvec3 &lo, const glm::dvec3 &hi) const;

    bool empty() const { return empty_; }

  private:
    RayCaster(const TriangleMesh *borrowed, TriangleMesh owned, Rays rays);  // on `borrowed`, or `owned` when null

    struct Impl;
    std::unique_ptr<Impl> impl_;
    bool empty_;
};

}  // namespace firn
