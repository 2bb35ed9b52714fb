#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

namespace firn {

// The top of the snow seen from above: per column (x, y) of trilinear cells (index space; cell c holds the points
// whose floor is c, its corners c + {0, 1}^3), the highest cell z whose corners hold a non-zero density. Above it
// the density is exactly 0, so a ray rising out of the snow that passes above every column's ceiling where it
// crosses that column reads no snow at all: most surface patches' sky rays (83 % of their column steps on the car,
// docs/benchmarks.md), proven empty by a walk over this 2-D map once the 3-D column walk has left the snow's
// leaves (Medium::ColumnMarcher::column). Built with the medium, 4 bytes per column of the active box (and 4 per
// tile of 8 x 8 and 64 x 64 columns).
class SnowCeiling {
  public:
    explicit SnowCeiling(const openvdb::FloatGrid &density);

    // True only if the density is 0 at every point ijk + t * direction, t >= 0 (index space; direction unit,
    // rising: direction.z > 0); false proves nothing (the ray may still cross no snow).
    bool clearAbove(const glm::dvec3 &ijk, const glm::dvec3 &direction) const;

    // The highest cell z over the cell column (x, y) whose corners hold a non-zero density; below every cell
    // (kNone) where none does.
    int ceiling(int x, int y) const;
    std::size_t bytes() const;

    static constexpr int kNone = -(1 << 30);

  private:
    openvdb::Coord min_;  // the map's first cell column (z unused)
    int nx_ = 0, ny_ = 0;
    // Columns of a map always built; beyond it, at most one per active voxel (4 bytes per voxel).
    static constexpr double kFewColumns = 65536.0;
    bool mapped_ = false;
    int highest_ = kNone;  // the highest ceiling of all
    std::vector<int> ceiling_;  // x fastest
    // The highest ceiling per aligned tile of kTileEdges columns (from min_), over the tile widened by one column
    // each side (a walk's points near a tile's edge may round into the next): proven rays cross a tile at a time.
    static constexpr std::array<int, 2> kTileEdges{64, 8};
    struct Tiles {
        int nx = 0, ny = 0;
        std::vector<int> highest;
    };
    std::array<Tiles, 2> tiles_;
    // The ray's parameter (voxels) where it leaves the tile of `edge` columns holding (x, y); from index-space o.
    double tileExit(const glm::dvec3 &o, const glm::dvec3 &direction, int tx, int ty, int edge) const;
};

}  // namespace firn
