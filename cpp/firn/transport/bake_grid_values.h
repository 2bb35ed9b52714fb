#pragma once

// What the source grids hold beyond the unknowns, and the grids written from it.

#include <algorithm>
#include <cstddef>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/bake.h"
#include "firn/transport/bake_preset.h"
#include "firn/transport/bake_source_function.h"
#include "firn/transport/bake_traced_voxels.h"
#include "firn/transport/baked_grids.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/transport/source_lobe.h"

namespace firn::bake {

struct VoxelValue {
    openvdb::Index offset;  // in its leaf
    BroadLobe lobe;
};

// One block's source functions at voxels, in order, built by one thread before the blocks are joined
// (VoxelValues::appendAll): its peaked lobes keyed by their place in it.
struct VoxelValueBlock {
    UnwrittenVector<VoxelValue> values;
    PeakedLobes::Peaks peaks;

    void add(openvdb::Index offset, const Source &S) {
        PeakedLobes::append(peaks, values.size(), S);
        values.push_back({offset, S});
    }
};

// Source functions at voxels, in order: broad lobes, with the peaked lobes by place (PeakedLobes).
struct VoxelValues {
    UnwrittenVector<VoxelValue> values;
    PeakedLobes peaked;

    // The blocks' values after these, block by block (consumed; the values copied in parallel, each page first
    // touched by the thread that copies into it: appended one by one they were the gathering's and the grids' largest
    // single-threaded step on the car, docs/benchmarks.md lead-80); returns where each block's values begin, and
    // where the last one's end.
    std::vector<std::size_t> appendAll(std::vector<VoxelValueBlock> &&blocks) {
        std::vector<std::size_t> start{values.size()};
        std::vector<const PeakedLobes::Peaks *> peaks;  // block b's keys shifted by start[b]
        for (const VoxelValueBlock &block : blocks) {
            peaks.push_back(&block.peaks);
            start.push_back(start.back() + block.values.size());
        }
        peaked.appendAll(peaks, start);
        values.resize(start.back());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 16), [&](const auto &range) {
            for (std::size_t b = range.begin(); b != range.end(); ++b) {
                std::copy(blocks[b].values.begin(), blocks[b].values.end(), values.begin() + start[b]);
                blocks[b] = VoxelValueBlock();  // (= {} would keep its capacity)
            }
        });
        return start;
    }
    Source operator[](std::size_t k) const { return peaked.with(values[k].lobe, k); }
};

// Values by leaf of the grids' topology: leaf l's lie at [start[l], start[l + 1]) and, where a second block was
// appended after the first, at [later[l], later[l + 1]).
struct LeafValues : VoxelValues {
    std::vector<std::size_t> start, later;

    // One block: perLeaf's values leaf by leaf (consumed), with room for `more` values after them, so that a
    // second block appended within it does not move the first (the old array and the new together were the car's
    // gathering peak). Room never written holds no memory (the pages of a large array are the system's until used).
    LeafValues(std::vector<VoxelValueBlock> &&perLeaf, std::size_t more) {
        std::size_t total = 0;
        for (const auto &leaf : perLeaf) total += leaf.values.size();
        values.reserve(total + more);
        start = appendAll(std::move(perLeaf));
        later.assign(start.size(), values.size());
    }
    // first's block taken over as it is (a copy of it was the gathering's and the grids' memory peak), then
    // `then`'s values leaf by leaf (consumed).
    LeafValues(LeafValues &&first, std::vector<VoxelValueBlock> &&then)
        : VoxelValues(std::move(first)), start(std::move(first.start)) {
        std::size_t total = values.size();
        for (const auto &leaf : then) total += leaf.values.size();
        values.reserve(total);
        later = appendAll(std::move(then));
    }
    template <typename Body>
    void forEachIn(std::size_t l, const Body &body) const {  // body(k) for leaf l's values
        for (std::size_t k = start[l]; k < start[l + 1]; ++k) body(k);
        for (std::size_t k = later[l]; k < later[l + 1]; ++k) body(k);
    }
    bool emptyIn(std::size_t l) const { return start[l] == start[l + 1] && later[l] == later[l + 1]; }
};

// What the source grids hold, worked out once so that the grids can be written one at a time (a grid at
// the density's resolution takes 12 bytes for every voxel of its leaves: the four of one lobe took ~250 bytes per
// unknown on the car sample, docs/bake.md Memory).
// Over the snow's voxels and a margin of three: unknowns hold their source function. Outside them (the
// density ramp and surface fringes) the radiance of the nearest surface voxels is carried out two voxels, so
// the renderer's trilinear ramp sees a constant ratio of emission to extinction; voxels too thin for the
// solve, away from any surface, hold their single scattering; the outermost ring holds zeros (Cycles reads
// Vec3 grids' edges wrongly).
struct GridValues {
    openvdb::BoolTree::Ptr topology;  // the snow's voxels and the margin
    // Voxels other than the unknowns (traced unknowns among them), leaf by leaf: those holding a surface's
    // radiance or a traced source, then those one voxel further out and thin snow on its own.
    std::optional<LeafValues> beyond;
    openvdb::Int32Tree::Ptr at;  // voxel -> its place in beyond, -1 elsewhere
};

// What the source grids hold beyond the unknowns (`gathering`: what the gathering between snow surfaces reads).
// Stops with firn::Cancelled when `progress` is cancelled.
GridValues gridValues(const Scene &scene, const SnowTopology &topo, const SourceValues &source,
                      const MonteCarloVoxels &traced, const Preset &preset, const BakeSettings &settings,
                      bool gathering, const SubProgress &progress);

// Grid k of BakedGrids' value from a source function: the broad lobe's four (l0, then l1 per axis), then the
// peaked lobe's p0 and p1.
inline openvdb::Vec3f broadComponent(const BroadLobe &S, int k) {
    return k == 0 ? openvdb::Vec3f(S.l0.x, S.l0.y, S.l0.z)
                  : openvdb::Vec3f(S.l1[0][k - 1], S.l1[1][k - 1], S.l1[2][k - 1]);
}
inline openvdb::Vec3f sourceComponent(const Source &S, int k) {
    return k < 4 ? broadComponent(S, k) : k == 4 ? openvdb::Vec3f(S.peak0.x, S.peak0.y, S.peak0.z)
                                                 : openvdb::Vec3f(S.peak1.x, S.peak1.y, S.peak1.z);
}

// Grid k of BakedGrids from its tree, `scale` times the voxel size of `density`, with its metadata.
openvdb::Vec3fGrid::Ptr sourceGrid(openvdb::Vec3fTree::Ptr tree, int k, int scale, const openvdb::FloatGrid &density,
                                   double extinctionPerDensity, const BakeSettings &settings);

// BakedGrids::scatter from its tree of scattered density (scatteredDensity), on voxels BakedGrids::kScatterScale
// times the density's, with the bake's metadata.
openvdb::FloatGrid::Ptr scatterGrid(openvdb::FloatTree::Ptr scattered, const openvdb::FloatGrid &density,
                                    double extinctionPerDensity, const BakeSettings &settings);

// BakedGrids' values at a point of the density's index space before the grids are written: read from the
// unknowns' source and the values beyond them, trilinear as BoxSampler reads a grid (the same values, bit for
// bit). The last cell's corners are kept: the gathering's half-voxel steps read each cell about twice. One per
// thread.
class BakedValuesSampler {
  public:
    BakedValuesSampler(const SnowTopology &topo, const SourceValues &source, const MonteCarloVoxels &traced,
                       const GridValues &values)
        : source_(source), beyond_(*values.beyond), index_(*topo.index), traced_(traced), at_(*values.at) {}

    BakedGrids::Values operator()(const openvdb::Vec3d &ijk) {
        const openvdb::Coord lower = floorCoord(ijk);
        if (!cached_ || lower != cell_) fill(lower), cell_ = lower, cached_ = true;
        const openvdb::Vec3R uvw = ijk - lower.asVec3d();
        BakedGrids::Values out;
        for (int g = 0; g < int(BakedGrids::kCount); ++g)
            out[g] = openvdb::tools::BoxSampler::trilinearInterpolation(corners_[g], uvw);
        return out;
    }

    // The value at voxel c (what the grids hold there at the density's resolution).
    Source at(const openvdb::Coord &c) { return valueAt(placeOf(c)); }

  private:
    // Where a voxel's value lies: unknown `index` (source_), place `index` among the values beyond them (beyond_),
    // or nowhere (zero).
    struct Place {
        enum { kNone, kUnknown, kBeyond } kind = kNone;
        std::size_t index = 0;
    };
    Place placeOf(const openvdb::Coord &c) {
        if (const std::int32_t i = index_.getValue(c); i >= 0 && traced_.getValue(c) < 0)
            return {Place::kUnknown, std::size_t(i)};
        const std::int32_t k = at_.getValue(c);
        return k >= 0 ? Place{Place::kBeyond, std::size_t(k)} : Place{};
    }
    Source valueAt(const Place &place) const {
        return place.kind == Place::kUnknown  ? source_[place.index]
               : place.kind == Place::kBeyond ? beyond_[place.index]
                                              : Source{};
    }
    template <typename T>
    static void prefetch(const T *value) {  // both cache lines a value may straddle
        __builtin_prefetch(value);
        __builtin_prefetch(reinterpret_cast<const char *>(value) + sizeof(T) - 1);
    }
    // The cell's eight corners. Those the last cell shares (a step into the next cell shares four) are kept; the
    // others are all found first and their broad lobes asked of memory together, then read (one after another,
    // each read waited on the last: the car's gathering spent 40 % of its time there).
    void fill(const openvdb::Coord &lower) {
        const openvdb::Coord shift = lower - cell_;  // the last cell's corner of this cell's corner o: o + shift
        const auto shared = [&](const openvdb::Coord &o) {
            const openvdb::Coord from = o + shift;
            return cached_ && from.x() >= 0 && from.x() <= 1 && from.y() >= 0 && from.y() <= 1 && from.z() >= 0 &&
                   from.z() <= 1;
        };
        openvdb::Vec3f last[BakedGrids::kCount][2][2][2];
        std::copy(&corners_[0][0][0][0], &corners_[0][0][0][0] + sizeof(last) / sizeof(last[0][0][0][0]),
                  &last[0][0][0][0]);
        Place places[8];
        for (int n = 0; n < 8; ++n) {
            const openvdb::Coord o(n >> 2, (n >> 1) & 1, n & 1);
            if (shared(o)) continue;
            places[n] = placeOf(lower + o);
            if (places[n].kind == Place::kUnknown) prefetch(&source_.broad[places[n].index]);
            if (places[n].kind == Place::kBeyond) prefetch(&beyond_.values[places[n].index]);
        }
        for (int n = 0; n < 8; ++n) {
            const openvdb::Coord o(n >> 2, (n >> 1) & 1, n & 1), from = o + shift;
            if (shared(o)) {
                for (int g = 0; g < int(BakedGrids::kCount); ++g)
                    corners_[g][o.x()][o.y()][o.z()] = last[g][from.x()][from.y()][from.z()];
                continue;
            }
            const Source S = valueAt(places[n]);
            for (int g = 0; g < int(BakedGrids::kCount); ++g)
                corners_[g][o.x()][o.y()][o.z()] = sourceComponent(S, g);
        }
    }

    const SourceValues &source_;
    const LeafValues &beyond_;
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index_;
    TracedIndex traced_;
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> at_;
    bool cached_ = false;
    openvdb::Coord cell_;  // the cell whose corners corners_ holds
    openvdb::Vec3f corners_[BakedGrids::kCount][2][2][2];
};

// The source grids at `scale` times the density's voxel size. Stops with firn::Cancelled when `progress` is
// cancelled.
BakedGrids makeGrids(const Scene &scene, const SnowTopology &topo, const SourceValues &source,
                     const MonteCarloVoxels &traced, const Preset &preset, const BakeSettings &settings, int scale,
                     const SubProgress &progress);

}  // namespace firn::bake
