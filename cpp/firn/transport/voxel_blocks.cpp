#include "firn/transport/voxel_blocks.h"

#include <algorithm>
#include <array>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace firn {

namespace {

// floor(v / 2^k), negative v included.
int floorShift(int v, int k) { return v >= 0 ? v >> k : ~((~v) >> k); }
openvdb::Coord floorShift(const openvdb::Coord &c, int k) {
    return openvdb::Coord(floorShift(c.x(), k), floorShift(c.y(), k), floorShift(c.z(), k));
}

// The first row of each run of rows in one region of edge 2^log2Edge, then the row count; empty unless every
// region's rows are one run.
std::vector<std::size_t> wholeRegionRuns(const UnwrittenVector<openvdb::Coord> &voxels, int log2Edge) {
    std::vector<std::size_t> start;
    std::vector<openvdb::Coord> region;
    for (std::size_t i = 0; i < voxels.size(); ++i) {
        const openvdb::Coord r = floorShift(voxels[i], log2Edge);
        if (region.empty() || r != region.back()) start.push_back(i), region.push_back(r);
    }
    std::sort(region.begin(), region.end());
    if (std::adjacent_find(region.begin(), region.end()) != region.end()) return {};
    start.push_back(voxels.size());
    return start;
}

// The edges tried, largest first (log2): a block's 2^3 voxels lie in one region of each.
constexpr std::array<int, 3> kLog2Edges{3, 2, 1};

// The regions' runs (wholeRegionRuns) of the largest edge that has them, and that edge (log2; 0 if none).
std::vector<std::size_t> largestWholeRuns(const UnwrittenVector<openvdb::Coord> &voxels, int &log2Edge) {
    for (int k : kLog2Edges)
        if (std::vector<std::size_t> runs = wholeRegionRuns(voxels, k); !runs.empty()) return log2Edge = k, runs;
    log2Edge = 0;
    return {};
}

// First appearance, serially: an index tree of the blocks met so far.
VoxelBlocks blocksInOrder(const UnwrittenVector<openvdb::Coord> &voxels) {
    VoxelBlocks out;
    const std::size_t n = voxels.size();
    openvdb::Int32Tree index(-1);
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> access(index);
    out.ofRow.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const openvdb::Coord block = floorShift(voxels[i], 1);
        int id = access.getValue(block);
        if (id < 0) {
            id = int(out.coord.size());
            access.setValue(block, id);
            out.coord.push_back(block);
        }
        out.ofRow[i] = std::uint32_t(id);
    }
    const std::size_t nc = out.coord.size();
    out.membersStart.assign(nc + 1, 0);
    for (std::uint32_t a : out.ofRow) ++out.membersStart[a + 1];
    for (std::size_t I = 0; I < nc; ++I) out.membersStart[I + 1] += out.membersStart[I];
    out.members.resize(n);
    std::vector<std::uint32_t> fill(out.membersStart.begin(), out.membersStart.end() - 1);
    for (std::size_t i = 0; i < n; ++i) out.members[fill[out.ofRow[i]]++] = std::uint32_t(i);
    return out;
}

// Run by run (`runs`: wholeRegionRuns of edge 2^log2Edge): a run's blocks are numbered after the earlier runs' and
// hold its rows alone, so each run numbers its own (at most 64) and places them after a sum of the counts.
VoxelBlocks blocksByRuns(const UnwrittenVector<openvdb::Coord> &voxels, const std::vector<std::size_t> &runs,
                         int log2Edge) {
    const std::size_t runCount = runs.size() - 1;
    const int side = 1 << (log2Edge - 1);  // blocks along a region's edge
    constexpr std::size_t kMostBlocks = 64;  // in a region of 8^3 voxels
    // A block's place in its region (row-major in its region's side^3 blocks).
    const auto placeInRegion = [&](const openvdb::Coord &c) {
        const openvdb::Coord block = floorShift(c, 1), region = floorShift(c, log2Edge);
        const openvdb::Coord at = block - openvdb::Coord(region.x() * side, region.y() * side, region.z() * side);
        return std::size_t((at.x() * side + at.y()) * side + at.z());
    };
    const auto eachRun = [&](const auto &body) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runCount, 64), [&](const auto &range) {
            for (std::size_t r = range.begin(); r != range.end(); ++r) body(r, runs[r], runs[r + 1]);
        });
    };
    VoxelBlocks out;
    out.ofRow.resize(voxels.size());
    std::vector<std::uint32_t> first(runCount + 1, 0);  // each run's first block
    eachRun([&](std::size_t r, std::size_t begin, std::size_t end) {  // the run's own numbers, in ofRow
        std::array<std::int8_t, kMostBlocks> local;
        local.fill(-1);
        std::int8_t count = 0;
        for (std::size_t i = begin; i < end; ++i) {
            std::int8_t &id = local[placeInRegion(voxels[i])];
            if (id < 0) id = count++;
            out.ofRow[i] = std::uint32_t(id);
        }
        first[r + 1] = std::uint32_t(count);
    });
    for (std::size_t r = 0; r < runCount; ++r) first[r + 1] += first[r];
    const std::size_t nc = first.back();
    out.coord.resize(nc);
    out.membersStart.resize(nc + 1);
    out.members.resize(voxels.size());
    out.membersStart[nc] = std::uint32_t(voxels.size());
    eachRun([&](std::size_t r, std::size_t begin, std::size_t end) {
        const std::size_t blocks = first[r + 1] - first[r];
        std::array<std::uint32_t, kMostBlocks + 1> start{};  // the run's blocks' members, from begin
        for (std::size_t i = begin; i < end; ++i) ++start[out.ofRow[i] + 1];
        for (std::size_t k = 0; k < blocks; ++k) start[k + 1] += start[k];
        for (std::size_t k = 0; k < blocks; ++k) out.membersStart[first[r] + k] = std::uint32_t(begin + start[k]);
        for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t k = out.ofRow[i];
            if (start[k] + begin == out.membersStart[first[r] + k]) out.coord[first[r] + k] = floorShift(voxels[i], 1);
            out.members[begin + start[k]++] = std::uint32_t(i);
            out.ofRow[i] = first[r] + k;
        }
    });
    return out;
}

}  // namespace

int contiguousRegionEdge(const UnwrittenVector<openvdb::Coord> &voxels) {
    int log2Edge = 0;
    largestWholeRuns(voxels, log2Edge);
    return log2Edge ? 1 << log2Edge : 0;
}

VoxelBlocks voxelBlocks(const UnwrittenVector<openvdb::Coord> &voxels) {
    int log2Edge = 0;
    const std::vector<std::size_t> runs = largestWholeRuns(voxels, log2Edge);
    return log2Edge ? blocksByRuns(voxels, runs, log2Edge) : blocksInOrder(voxels);
}

}  // namespace firn
