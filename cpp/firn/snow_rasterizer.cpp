#include "firn/snow_rasterizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <sstream>

#include <glm/geometric.hpp>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "firn/error.h"
#include "firn/metaball.h"
#include "firn/vdb_io.h"

namespace firn {

namespace {

using FloatTree = openvdb::FloatTree;
using FloatLeaf = FloatTree::LeafNodeType;
constexpr int kLeafDim = FloatLeaf::DIM;  // 8
constexpr int kLeafVoxels = FloatLeaf::SIZE;
constexpr double kSurfaceBandVoxels = 3.0;  // half-width of the surface level set

// Leaf coordinates (index / 8) packed into 64 bits, 21 bits per axis.
constexpr std::int64_t kKeyBias = 1 << 20;
std::uint64_t leafKey(const openvdb::Coord &leaf) {
    return (std::uint64_t(leaf.x() + kKeyBias) << 42) | (std::uint64_t(leaf.y() + kKeyBias) << 21) |
           std::uint64_t(leaf.z() + kKeyBias);
}
openvdb::Coord leafOrigin(std::uint64_t key) {
    const auto axis = [&](int shift) { return int(std::int64_t((key >> shift) & ((1u << 21) - 1)) - kKeyBias); };
    return openvdb::Coord(axis(42) * kLeafDim, axis(21) * kLeafDim, axis(0) * kLeafDim);
}

struct LeafRange {
    openvdb::CoordBBox leaves;  // in leaf coordinates
};

LeafRange leavesOf(const Metaball &b, double h) {
    const glm::dvec3 lo = (glm::dvec3(b.centre) - double(b.radius)) / h;
    const glm::dvec3 hi = (glm::dvec3(b.centre) + double(b.radius)) / h;
    const auto toLeaf = [](double x) { return int(std::floor(std::floor(x) / kLeafDim)); };
    return {openvdb::CoordBBox(openvdb::Coord(toLeaf(lo.x), toLeaf(lo.y), toLeaf(lo.z)),
                               openvdb::Coord(toLeaf(hi.x + 1), toLeaf(hi.y + 1), toLeaf(hi.z + 1)))};
}

std::string millions(double n) {
    std::ostringstream s;
    s.precision(3);
    s << n / 1e6 << " million";
    return s.str();
}

}  // namespace

void checkVoxelBudget(double voxels, const RasterSettings &s) {
    if (voxels <= s.maxVoxels) return;
    const double suggested = s.voxelSize * std::cbrt(voxels / s.maxVoxels) * 1.1;
    std::ostringstream msg;
    msg.precision(3);
    msg << "this snow needs about " << millions(voxels) << " voxels at voxel size " << s.voxelSize
        << " m, over the budget of " << millions(s.maxVoxels) << ": use a voxel size of at least " << suggested
        << " m (or raise the voxel budget in Firn's preferences)";
    throw BudgetExceeded(msg.str());
}

namespace {

// (leaf key, ball index) pairs, sorted: each leaf's balls in a fixed order, whatever the thread count.
std::vector<std::pair<std::uint64_t, std::uint32_t>> binBallsByLeaf(const std::vector<Metaball> &balls, double h) {
    std::vector<std::size_t> offsets(balls.size() + 1, 0);
    tbb::parallel_for(std::size_t(0), balls.size(),
                      [&](std::size_t i) { offsets[i + 1] = leavesOf(balls[i], h).leaves.volume(); });
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs(offsets.back());
    tbb::parallel_for(std::size_t(0), balls.size(), [&](std::size_t i) {
        std::size_t at = offsets[i];
        const openvdb::CoordBBox box = leavesOf(balls[i], h).leaves;
        for (auto it = box.begin(); it; ++it) pairs[at++] = {leafKey(*it), std::uint32_t(i)};
    });
    tbb::parallel_sort(pairs.begin(), pairs.end());
    return pairs;
}

// Field and field-weighted depth of one leaf's voxels, from the balls that reach it.
struct LeafField {
    std::array<float, kLeafVoxels> field{};      // sum of clipped ball fields
    std::array<float, kLeafVoxels> depth{};      // m below the snow top, field-weighted
    std::array<bool, kLeafVoxels> inside{};      // within some ball's sphere (active)
};

void gatherLeaf(const openvdb::Coord &origin, const std::uint32_t *ballIds, std::size_t count,
                const std::vector<Metaball> &balls, double h, LeafField &out) {
    std::array<double, kLeafVoxels> field{}, weightedDepth{};
    const float hf = float(h);
    const int zLeafLo = origin.z(), zLeafHi = origin.z() + kLeafDim - 1;
    for (std::size_t n = 0; n < count; ++n) {
        const Metaball &b = balls[ballIds[n]];
        const glm::vec3 c = b.centre, normal = b.normal;
        const float r2 = b.radius * b.radius, invR2 = 1.0f / r2;
        const float clipHeight = -b.base - 2.0f * hf;  // below this, no field; keep a 2-voxel exterior band
        const int xLo = std::max(origin.x(), int(std::ceil((c.x - b.radius) / hf)));
        const int xHi = std::min(origin.x() + kLeafDim - 1, int(std::floor((c.x + b.radius) / hf)));
        const int yLo = std::max(origin.y(), int(std::ceil((c.y - b.radius) / hf)));
        const int yHi = std::min(origin.y() + kLeafDim - 1, int(std::floor((c.y + b.radius) / hf)));
        for (int x = xLo; x <= xHi; ++x) {
            const float dx = x * hf - c.x;
            for (int y = yLo; y <= yHi; ++y) {
                const float dy = y * hf - c.y;
                const float rest = r2 - dx * dx - dy * dy;
                if (rest <= 0.0f) continue;
                // The z-range inside the sphere and above the clip plane (when the plane is not vertical).
                const float half = std::sqrt(rest);
                float zLo = c.z - half;
                const float lateral = normal.x * dx + normal.y * dy;
                if (normal.z > 0.05f) zLo = std::max(zLo, c.z + (clipHeight - lateral) / normal.z);
                const int kLo = std::max(zLeafLo, int(std::ceil(zLo / hf)));
                const int kHi = std::min(zLeafHi, int(std::floor((c.z + half) / hf)));
                const int row = ((x - origin.x()) << 6) | ((y - origin.y()) << 3);
                for (int z = kLo; z <= kHi; ++z) {
                    const float dz = z * hf - c.z;
                    const float d2 = dx * dx + dy * dy + dz * dz;
                    if (d2 >= r2) continue;
                    const int i = row + (z - zLeafLo);
                    out.inside[i] = true;
                    const float height = lateral + normal.z * dz;  // m above the centre along the normal
                    if (height < -b.base) continue;                // below the surface the ball stands on
                    const double f = wyvillField(d2 * invR2);
                    field[i] += f;
                    weightedDepth[i] += f * (b.depth - height);
                }
            }
        }
    }
    for (int i = 0; i < kLeafVoxels; ++i) {
        out.field[i] = float(field[i]);
        out.depth[i] = field[i] > 0.0 ? float(std::max(0.0, weightedDepth[i] / field[i])) : 0.0f;
    }
}

// Narrow-band level set of the iso-surface field = iso, by the first-order distance (iso - F) / |grad F|
// (central differences), clamped to +-band: exact for a planar field, within a fraction of a voxel near the
// surface, and a single parallel pass (OpenVDB's fast sweeping costs ten times more here for nothing
// the density or the mesh needs).
openvdb::FloatGrid::Ptr signedDistanceBand(const openvdb::FloatGrid &field, double iso, double band) {
    const double h = field.voxelSize()[0];
    auto sdf = field.deepCopy();
    sdf->setName("surface");
    sdf->setGridClass(openvdb::GRID_LEVEL_SET);
    sdf->tree().root().setBackground(float(band), true);  // voxels no ball reaches: outside
    openvdb::tree::LeafManager<FloatTree> manager(sdf->tree());
    manager.foreach([&](FloatLeaf &leaf, std::size_t) {
        auto f = field.getConstAccessor();
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            double g2 = 0.0;
            for (int a = 0; a < 3; ++a) {
                openvdb::Coord step(0);
                step[a] = 1;
                const double g = (f.getValue(c + step) - f.getValue(c - step)) / (2.0 * h);
                g2 += g * g;
            }
            const double distance = (iso - f.getValue(c)) / std::max(std::sqrt(g2), 1e-12);
            it.setValue(float(std::clamp(distance, -band, band)));
            if (std::abs(distance) >= band) it.setValueOff();
        }
    });
    openvdb::tools::pruneLevelSet(sdf->tree());
    return sdf;
}

openvdb::FloatGrid::Ptr makeGrid(const std::string &name, double h) {
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(name);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    return grid;
}

}  // namespace

double estimateVoxelCount(const std::vector<Metaball> &balls, double spacing, double voxelSize) {
    // Each ball adds one layer step (about half its radius) of snow over spacing^2 of surface, plus the
    // exterior shell of the top ball; 1.5x for edges, where balls overlap less.
    double volume = 0.0;  // m^3
    for (const Metaball &b : balls) volume += spacing * spacing * double(b.radius);
    return 1.5 * volume / std::pow(voxelSize, 3);
}

SnowGrids rasterizeSnow(const std::vector<Metaball> &balls, const RasterSettings &s, const SubProgress &progress) {
    initializeOpenVdb();
    const double h = s.voxelSize;
    if (!(h > 0.0) || !std::isfinite(h)) throw InvalidArgument("voxel size must be a positive number of metres");

    const auto pairs = binBallsByLeaf(balls, h);
    std::vector<std::size_t> starts;  // first pair of each leaf
    for (std::size_t i = 0; i < pairs.size(); ++i)
        if (i == 0 || pairs[i].first != pairs[i - 1].first) starts.push_back(i);
    const double leafVoxels = double(starts.size()) * kLeafVoxels;
    checkVoxelBudget(leafVoxels / 4.0, s);  // leaves are rarely less than a quarter full
    starts.push_back(pairs.size());
    progress.report(0.1);
    progress.throwIfCancelled();

    auto field = makeGrid("field", h);
    auto depth = makeGrid("depth", h);
    const std::size_t leafCount = starts.size() - 1;
    std::vector<FloatLeaf *> fieldLeaves(leafCount), depthLeaves(leafCount);
    for (std::size_t l = 0; l < leafCount; ++l) {
        const openvdb::Coord origin = leafOrigin(pairs[starts[l]].first);
        fieldLeaves[l] = field->tree().touchLeaf(origin);
        depthLeaves[l] = depth->tree().touchLeaf(origin);
    }
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leafCount, 64), [&](const tbb::blocked_range<std::size_t> &r) {
        progress.throwIfCancelled();
        std::vector<std::uint32_t> ids;
        LeafField leafField;
        for (std::size_t l = r.begin(); l != r.end(); ++l) {
            ids.clear();
            for (std::size_t p = starts[l]; p < starts[l + 1]; ++p) ids.push_back(pairs[p].second);
            leafField = LeafField{};
            const openvdb::Coord origin = fieldLeaves[l]->origin();
            gatherLeaf(origin, ids.data(), ids.size(), balls, h, leafField);
            for (int i = 0; i < kLeafVoxels; ++i) {
                fieldLeaves[l]->setValueOnly(i, leafField.field[i]);
                fieldLeaves[l]->setActiveState(i, leafField.inside[i]);
                depthLeaves[l]->setValueOnly(i, leafField.depth[i]);
                depthLeaves[l]->setActiveState(i, leafField.inside[i]);
            }
        }
        progress.report(0.1 + 0.5 * double(done += r.size()) / double(leafCount));
    });
    const double activeVoxels = double(field->activeVoxelCount());
    checkVoxelBudget(activeVoxels, s);
    progress.throwIfCancelled();

    SnowGrids grids;
    grids.surface = signedDistanceBand(*field, kSnowIsoValue, kSurfaceBandVoxels * h);
    progress.report(0.85);
    progress.throwIfCancelled();

    grids.density = field->deepCopy();
    grids.density->setName("density");
    grids.density->setGridClass(openvdb::GRID_FOG_VOLUME);
    openvdb::tree::LeafManager<FloatTree> manager(grids.density->tree());
    manager.foreach([&](FloatLeaf &leaf, std::size_t) {
        const FloatLeaf *sdf = grids.surface->tree().probeConstLeaf(leaf.origin());
        const FloatLeaf *below = depth->tree().probeConstLeaf(leaf.origin());
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const float d = sdf ? sdf->getValue(it.pos()) : float(kSurfaceBandVoxels * h);
            // Coverage of the voxel by snow: 1 inside, 0 outside, a one-voxel ramp centred on the surface,
            // so that Cycles' trilinear density crosses half at the iso-surface.
            const double coverage = std::clamp(0.5 - double(d) / h, 0.0, 1.0);
            if (coverage <= 0.0) {
                it.setValue(0.0f);
                it.setValueOff();
                continue;
            }
            it.setValue(float(coverage * s.compaction.density(below->getValue(it.pos()))));
        }
    });
    openvdb::tools::pruneInactive(grids.density->tree());
    grids.density->insertMeta("units", openvdb::StringMetadata("kg/m^3"));
    grids.surface->insertMeta("units", openvdb::StringMetadata("m"));
    progress.report(1.0);
    return grids;
}

}  // namespace firn
