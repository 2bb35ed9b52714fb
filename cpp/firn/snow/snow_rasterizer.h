#pragma once

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/snow/compaction.h"
#include "firn/snow/metaball_layout.h"
#include "firn/util/progress.h"

namespace firn {

// The snow's grids in world space (contract: docs/vdb-contract.md).
struct SnowGrids {
    openvdb::FloatGrid::Ptr density;  // kg/m^3, zero outside the snow
    openvdb::FloatGrid::Ptr surface;  // level set: signed distance to the snow surface (m), negative inside
};

// The largest voxel budget any setting takes: past every machine's memory, a budget lets every check pass and an
// allocation fail (std::bad_alloc; inside OpenVDB's mesh-to-volume its unwinding terminated: fuzz seeds 324445, and
// spray 510591 with a budget of 1e30 and a track 2e7 m tall).
constexpr double kMaxVoxelBudget = 1e11;

struct RasterSettings {
    double voxelSize = 0.01;     // m
    double maxVoxels = 50e6;     // active voxels allowed before allocating
    CompactionProfile compaction;
};

// Active voxels the balls will need, estimated cheaply before anything is allocated.
double estimateVoxelCount(const std::vector<Metaball> &balls, double spacing, double voxelSize);

// Throws BudgetExceeded, with the voxel size that would fit, when `voxels` exceeds settings.maxVoxels; the
// message says the snow needs `quantifier` (about, at least) that many.
void checkVoxelBudget(double voxels, const RasterSettings &settings, const char *quantifier = "about");

// Sums the balls' fields on a sparse grid in one parallel, deterministic pass (each 8^3 leaf gathers the
// balls that reach it). Snow is where the field exceeds the iso-value and which lies above the surface the
// balls stand on; the level set is its signed distance, the density follows compaction by depth below the
// top, antialiased over one voxel at the surface. Throws BudgetExceeded, before allocating, when the leaves
// would hold more than maxVoxels.
SnowGrids rasterizeSnow(const std::vector<Metaball> &balls, const RasterSettings &settings,
                        const SubProgress &progress);

// Which balls reach each 8^3 leaf, by ball index in ascending order (the order rasterizeSnow sums them in, so
// that a leaf rasterized again alone comes out as the whole grid's pass made it). Kept up to date by the snow
// brush as balls come, go and move.
class LeafBallIndex {
  public:
    LeafBallIndex(const std::vector<Metaball> &balls, double voxelSize);
    void insert(std::uint32_t id, const Metaball &ball);  // into every leaf the ball reaches
    void erase(std::uint32_t id, const Metaball &ball);
    bool sameLeaves(const Metaball &a, const Metaball &b) const;  // both reach exactly the same leaves
    // Origins (index space) of the leaves a ball reaches, appended to `out`.
    void leavesOf(const Metaball &ball, std::vector<openvdb::Coord> &out) const;
    const std::vector<std::uint32_t> *ballsOf(const openvdb::Coord &leafOrigin) const;  // null: none

  private:
    double voxelSize_;  // m
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> leaves_;
};

// Rasterizes again only the leaves at `leafOrigins` (index space, unique) of grids that rasterizeSnow made, from
// the balls `index` says reach them; the rest of the grids is kept. A leaf left without snow becomes a tile, as
// rasterizeSnow's pruning makes it. Parallel over leaves; the grids change on the calling thread.
void rasterizeLeaves(const std::vector<Metaball> &balls, const LeafBallIndex &index,
                     const std::vector<openvdb::Coord> &leafOrigins, const RasterSettings &settings,
                     SnowGrids &grids);

}  // namespace firn
