#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/RayIntersector.h>

#include "firn/optics/transport_scales.h"  // validate(VolumeOptics)
#include "firn/optics/volume_optics.h"

namespace firn {

// The cell (voxel index) holding a point of index space: floor of each coordinate, without std::floor's
// rounding-mode work (marches call it for every sample).
inline openvdb::Coord floorCoord(const openvdb::Vec3d &ijk) {
    auto floorInt = [](double x) {
        const int i = int(x);
        return i - int(x < double(i));
    };
    return openvdb::Coord(floorInt(ijk.x()), floorInt(ijk.y()), floorInt(ijk.z()));
}

// The snow as light sees it: sigma_t(x) = k * density(x) (1/m), with the density interpolated trilinearly
// between voxel centres in world space, exactly as Cycles reads the grid. Every transport code in Firn
// (the bake, the Monte Carlo reference, the baked-radiance renderer) samples this one definition.
class Medium {
  public:
    using Accessor = openvdb::FloatGrid::ConstAccessor;

    // Validates: uniform, axis-aligned voxels; background 0; finite, non-negative densities; optics sane.
    // Active tiles are voxelized (on a copy).
    Medium(openvdb::FloatGrid::ConstPtr density, const VolumeOptics &optics);
    ~Medium();

    const openvdb::FloatGrid &density() const { return *density_; }
    const VolumeOptics &optics() const { return optics_; }
    double voxelSize() const { return h_; }  // m
    double maxDensity() const { return maxDensity_; }  // kg/m^3
    double maxSigmaT() const { return optics_.extinctionPerDensity * maxDensity_; }  // 1/m

    glm::dvec3 indexToWorld(const glm::dvec3 &ijk) const { return origin_ + h_ * ijk; }
    glm::dvec3 worldToIndex(const glm::dvec3 &p) const { return (p - origin_) / h_; }
    glm::dvec3 voxelCentre(const openvdb::Coord &c) const { return indexToWorld(glm::dvec3(c.x(), c.y(), c.z())); }

    // World box (m) outside which the density is zero: the active voxels' centres grown by one voxel.
    const glm::dvec3 &boundsMin() const { return boundsMin_; }
    const glm::dvec3 &boundsMax() const { return boundsMax_; }
    // Parametric range [t0, t1] (m) of the ray inside the bounds; false if it misses.
    bool clipToBounds(const glm::dvec3 &origin, const glm::dvec3 &direction, double &t0, double &t1) const;

    Accessor accessor() const { return density_->getConstAccessor(); }
    double densityAt(const glm::dvec3 &world, Accessor &accessor) const;  // kg/m^3, trilinear

    // Edge (cells) of the largest aligned block of 64^3, 32^3 or 16^3 cells that holds `cell` and no cell that may
    // hold snow; 0 if the 16^3 block holds one.
    int clearBlockEdge(const openvdb::Coord &cell) const;
    // Edge (cells) of the largest aligned block (64^3 down to the cell itself) that holds `cell` and no cell that
    // may hold snow; 0 if `cell` may hold snow.
    using SupportAccessor = openvdb::tree::ValueAccessor<const openvdb::BoolTree>;
    SupportAccessor supportAccessor() const { return SupportAccessor(*support_); }
    int emptyBlockEdge(const openvdb::Coord &cell, SupportAccessor &support) const;

    // The density (kg/m^3) at points of index space, trilinear as BoxSampler::sample reads it (densityAt: the same
    // value bit for bit), from the last cell's eight values when a point lies in the same cell: walks in half-voxel
    // steps read each cell about twice, tracking through dense snow (steps of a mean free path) a dozen times.
    // One per thread.
    class DensitySampler {
      public:
        explicit DensitySampler(const Medium &medium);
        double at(const openvdb::Vec3d &ijk) { return in(floorCoord(ijk), ijk); }
        double at(const glm::dvec3 &ijk) { return at(openvdb::Vec3d(ijk.x, ijk.y, ijk.z)); }
        // `cell`: floorCoord(ijk).
        double in(const openvdb::Coord &cell, const openvdb::Vec3d &ijk) {
            if (cell != cell_) {
                cell_ = cell;
                readCorners(cell);
            }
            return openvdb::tools::BoxSampler::trilinearInterpolation(corners_, ijk - cell.asVec3d());
        }

      private:
        // The cell's eight voxel values, as BoxSampler::getValues reads them: from the one leaf that holds them all
        // where there is one (7 cells in 8 per axis), else voxel by voxel through the accessor (eight tree walks).
        void readCorners(const openvdb::Coord &cell) {
            using Leaf = openvdb::FloatTree::LeafNodeType;
            constexpr int kLast = Leaf::DIM - 1;
            const Leaf *leaf = (cell.x() & kLast) < kLast && (cell.y() & kLast) < kLast && (cell.z() & kLast) < kLast
                                   ? accessor_.probeConstLeaf(cell)
                                   : nullptr;
            if (!leaf) {
                openvdb::tools::BoxSampler::getValues(corners_, accessor_, cell);
                return;
            }
            const openvdb::Index first = Leaf::coordToOffset(cell);
            for (int i = 0; i < 2; ++i)
                for (int j = 0; j < 2; ++j)
                    for (int k = 0; k < 2; ++k) {
                        const openvdb::Index offset = (i << (2 * Leaf::LOG2DIM)) + (j << Leaf::LOG2DIM) + k;
                        corners_[i][j][k] = leaf->getValue(first + offset);
                    }
        }

        Accessor accessor_;
        openvdb::Coord cell_;  // the cell whose eight density values corners_ holds
        float corners_[2][2][2];
    };

    // Integrates the density along rays (kg/m^2), skipping cells and blocks without snow. One per thread
    // (cheap copies).
    class ColumnMarcher {
      public:
        explicit ColumnMarcher(const Medium &medium);
        // The density (kg/m^3) at a point of index space (DensitySampler).
        double densityAt(const openvdb::Vec3d &ijk) { return density_.at(ijk); }
        // Mass column between t = 0 and tMax (m) along origin + t * direction (unit), midpoint rule on
        // half-voxel steps while the ray starts in snow, whole-voxel steps beyond; stops once the column exceeds
        // `limit` (kg/m^2) and returns what it has.
        double column(const glm::dvec3 &origin, const glm::dvec3 &direction, double tMax, double limit);
        // The steps column() has taken so far (each a density read, or a jump over cells without snow): its work
        // in tracking-step equivalents, for a budget (bake_traced_voxels.cpp, planGathering).
        long columnSteps() const { return columnSteps_; }

        // Walks the ray from t = 0 to tMax (m) in steps of at most `step` voxels, calling visit(midpoint in index
        // space, step length in m) where the density may be non-zero (the midpoints in cells without snow are
        // skipped, whole empty 2^3, 4^3 and 8^3 blocks at a time); stops when visit returns false.
        template <typename Visit>
        void march(const glm::dvec3 &origin, const glm::dvec3 &direction, double tMax, double step, Visit &&visit) {
            const glm::dvec3 start = medium_.worldToIndex(origin);
            const openvdb::math::Ray<double> ray(openvdb::Vec3d(start.x, start.y, start.z),
                                                 openvdb::Vec3d(direction.x, direction.y, direction.z), 0.0,
                                                 tMax / medium_.voxelSize());
            if (!intersector_.setIndexRay(ray)) return;
            double t0 = 0.0, t1 = 0.0;
            while (intersector_.march(t0, t1)) {
                const int steps = std::max(1, int(std::ceil((t1 - t0) / step)));
                const double dt = (t1 - t0) / steps;
                for (int i = 0; i < steps; ++i) {
                    const openvdb::Vec3d p = ray(t0 + (i + 0.5) * dt);
                    const int empty = lastEmptySample(ray, p, t0, dt, i, steps);
                    if (empty >= i) {
                        i = empty;
                        continue;
                    }
                    if (!visit(p, dt * medium_.voxelSize())) return;
                }
            }
        }

      private:
        // Samples ray(t0 + (j + 0.5) dt) of a walk (index space): if sample i, at p, lies in a cell without
        // snow, the last sample j >= i (below `steps`) still inside the largest empty aligned block (8^3, 4^3,
        // 2^3 or the cell) that holds p, so that the walk goes on after it; else i - 1. The samples skipped
        // would add nothing: the walk's values do not change.
        int lastEmptySample(const openvdb::math::Ray<double> &ray, const openvdb::Vec3d &p, double t0, double dt, int i,
                            int steps);
        // The support's leaf holding `cell` (null where none), the last one kept: a walk takes several steps in each
        // leaf, and the accessor's own cache sits behind a call and three levels' checks.
        using SupportLeaf = openvdb::BoolTree::LeafNodeType;
        // Compared and kept coordinate by coordinate: a Coord built on the stack and copied in one 8-byte load
        // stalled each change of leaf on the two 4-byte stores it read (store forwarding).
        const SupportLeaf *supportLeaf(const openvdb::Coord &cell) {
            constexpr int kOrigin = ~int(SupportLeaf::DIM - 1);
            const int x = cell.x() & kOrigin, y = cell.y() & kOrigin, z = cell.z() & kOrigin;
            if (x != leafOrigin_.x() || y != leafOrigin_.y() || z != leafOrigin_.z())
                leafOrigin_.reset(x, y, z), leaf_ = support_.probeConstLeaf(cell);
            return leaf_;
        }

        const Medium &medium_;
        openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid, 0> intersector_;
        DensitySampler density_;
        openvdb::tree::ValueAccessor<const openvdb::BoolTree> support_;
        openvdb::Coord leafOrigin_ = openvdb::Coord::max();  // supportLeaf's last leaf's origin (max: none yet)
        const SupportLeaf *leaf_ = nullptr;
        long columnSteps_ = 0;
    };

  private:
    openvdb::FloatGrid::ConstPtr density_;
    VolumeOptics optics_;
    double h_ = 0.0;
    glm::dvec3 origin_{0.0};
    double maxDensity_ = 0.0;
    glm::dvec3 boundsMin_{0.0}, boundsMax_{0.0};
    std::unique_ptr<openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid, 0>> intersector_;
    // Voxels c whose trilinear cell (corners c + {0, 1}^3) may hold snow: elsewhere the density is 0 without
    // reading eight voxels. Rays from the surface to the sky cross mostly such empty cells of occupied blocks.
    openvdb::BoolTree::Ptr support_;
    // Per level (blocks of 16^3, 32^3, 64^3 cells from blocksOrigin_): 1 where a block holds a leaf of support_,
    // a byte per block over the support's bounding box: rays leave the snow's neighbourhood in a few jumps.
    void markOccupiedBlocks();
    static constexpr std::array<int, 3> kBlockEdges{16, 32, 64}, kBlockLog2{4, 5, 6};
    openvdb::Coord blocksOrigin_;
    std::array<openvdb::Coord, 3> blockCounts_;
    std::array<std::vector<std::uint8_t>, 3> blockOccupied_;
};

}  // namespace firn
