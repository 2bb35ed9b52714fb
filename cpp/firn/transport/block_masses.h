#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

namespace firn {

// The snow's mass (kg) per aligned block of 4^3, 8^3, ... voxels (a mip of block masses over the grid's active
// bounding box), built once per bake, for its incident light only (computeIncidentLight): what lies beside a ray at
// a coarse scale, for the forward light a cloud sends along it (incident_light.cpp, Crossing::Spreading).
class BlockMasses {
  public:
    BlockMasses() = default;
    // density: kg/m^3 at voxel centres; h: voxel edge (m); origin: world position of voxel (0, 0, 0).
    BlockMasses(const openvdb::FloatGrid &density, double h, const glm::dvec3 &origin);

    // The mass column (kg/m^2) seen through a window of the Cauchy kernel K_s(rho) = 1/(2 pi s^2)
    // (1 + rho^2/s^2)^-3/2 across the ray from `point` along w (unit), of the snow between `near` and `far` (m)
    // along it: sum over blocks of mass x (the block's depth inside [near, far]) / edge x K_s'(rho), s'^2 = s^2 +
    // edge^2 / (2 pi) (the kernel smoothed by the block: 1 / edge^2 on the axis as s -> 0), at the coarsest level whose
    // edge is at most s, out to rho = 3 s', the kernel renormalised there; 0 where s is below the finest edge (the
    // blocks cannot tell a piece's neighbours from the snow beyond its cone). In a uniform cloud it is the column along the
    // ray; beside a lone small piece its mass times K_s(0).
    double windowedColumn(const glm::dvec3 &point, const glm::dvec3 &w, double near, double far, double s) const;

    // The block masses held over all levels (4 bytes each): at most 8/7 of max(2^22, active voxels / 4), the finest
    // blocks coarser than 4^3 voxels where the active box would need more.
    std::size_t storedBlocks() const;

  private:
    struct Level {
        std::int64_t edge = 0;     // voxels per block edge
        openvdb::Coord count;      // blocks per axis
        std::vector<float> mass;   // kg, x fastest
        float at(int i, int j, int k) const { return mass[(std::size_t(k) * count.y() + j) * count.x() + i]; }
    };
    double h_ = 0.0;
    glm::dvec3 origin_{0.0};
    glm::dvec3 firstCorner_{0.0};  // the first block's lowest voxel (index space)
    std::vector<Level> levels_;
};

}  // namespace firn
