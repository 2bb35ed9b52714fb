#pragma once

#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

namespace firn {

class Medium;

// The top of the snow seen from above: per column (x, y) of trilinear cells (index space; cell c holds the points
// whose floor is c, its corners c + {0, 1}^3), the highest cell z whose corners hold a non-zero density. Above it
// the density is exactly 0, so a ray rising out of the snow that passes above every column's ceiling where it
// crosses that column reads no snow at all: most surface patches' sky rays (83 % of their column steps on the car,
// docs/benchmarks.md), proven empty by a walk over this 2-D map instead of the 3-D column walk. Built once per bake
// (computeIncidentLight), 4 bytes per column of the active box.
class SnowCeiling {
  public:
    explicit SnowCeiling(const Medium &medium);

    // True only if the density is 0 at every point origin + t * direction, t >= 0 (origin in m; direction unit,
    // rising: direction.z > 0); false proves nothing (the ray may still cross no snow).
    bool clearAbove(const glm::dvec3 &origin, const glm::dvec3 &direction) const;

    // The highest cell z over the cell column (x, y) whose corners hold a non-zero density; below every cell
    // (kNone) where none does.
    int ceiling(int x, int y) const;
    std::size_t bytes() const { return ceiling_.capacity() * sizeof(int); }

    static constexpr int kNone = -(1 << 30);

  private:
    const Medium &medium_;
    openvdb::Coord min_;  // the map's first cell column (z unused)
    int nx_ = 0, ny_ = 0;
    int highest_ = kNone;  // the highest ceiling of all
    std::vector<int> ceiling_;  // x fastest
};

}  // namespace firn
