#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

namespace firn {

// The snow's mass (kg) per aligned block of 4^3, 8^3, ... voxels (a mip of block masses over the grid's active
// bounding box), built once per medium: what lies beside a ray at a coarse scale, for the forward light a cloud
// sends along it (incident_light.cpp, Crossing::Spreading).
class BlockMasses {
  public:
    BlockMasses() = default;
    // density: kg/m^3 at voxel centres; h: voxel edge (m); origin: world position of voxel (0, 0, 0).
    BlockMasses(const openvdb::FloatGrid &density, double h, const glm::dvec3 &origin);

    // The mean of response(c) over the snow's columns c (kg/m^2) beside the ray from `point` along w (unit) between
    // `near` and `far` (m) along it, weighted by the Cauchy kernel K_s(rho) = (1 + rho^2/s^2)^-3/2 across the ray:
    // the blocks' masses (x their depth inside [near, far] over their extent along w) gathered bilinearly onto a
    // grid of square cells across the ray (the block's edge, or a sixth of the window's reach where wider), each
    // cell's mass over its area its column, the kernel smoothed by the block (s'^2 = s^2 + edge^2 / (2 pi): 1 /
    // edge^2 on the axis as s -> 0) and cut at rho = 3 s', at the coarsest level whose edge is at most s. response
    // must be 0 at 0 (empty cells count with their weight only). 0 where s is below the finest edge (the blocks
    // cannot tell a piece's neighbours from the snow beyond its cone). With the identity response: in a uniform
    // cloud the column along the ray; beside a lone small piece its mass times K_s(0) (normalised).
    glm::dvec3 windowedMean(const glm::dvec3 &point, const glm::dvec3 &w, double near, double far, double s,
                            const std::function<glm::dvec3(double)> &response) const;

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
