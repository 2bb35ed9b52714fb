#include "firn/snow/snow_rasterizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <sstream>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <openvdb/tools/Prune.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "firn/geometry/metaball.h"
#include "firn/util/error.h"
#include "firn/util/openvdb_library.h"

namespace firn {

namespace {

using FloatTree = openvdb::FloatTree;
using FloatLeaf = FloatTree::LeafNodeType;
constexpr int kLeafDim = FloatLeaf::DIM;  // 8
constexpr int kLeafVoxels = FloatLeaf::SIZE;
constexpr double kSurfaceBandVoxels = 3.0;  // half-width of the surface level set
constexpr double kMinVoxelSize = 1e-4;      // m

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

// Whether ball b can add anything to the leaf at leaf coordinates `leaf` (gatherLeaf adds only inside the sphere
// and above the ball's lowest height): its sphere meets the box of the leaf's voxels, and the box's highest corner
// along the normal is not below that height. In double, with a thousandth of a voxel to spare for the gather's
// float rounding. Of the leaves a ball's box spans, some 45 % fail (corners outside the sphere, leaves under the
// surface the ball stands on).
bool reaches(const Metaball &b, const openvdb::Coord &leaf, double h) {
    const double margin = 1e-3 * h;
    const glm::dvec3 lo = glm::dvec3(leaf.x(), leaf.y(), leaf.z()) * double(kLeafDim) * h;
    const glm::dvec3 hi = lo + double(kLeafDim - 1) * h;
    const glm::dvec3 c(b.centre), n(b.normal);
    const glm::dvec3 nearest = glm::clamp(c, lo, hi) - c;
    const double reach = double(b.radius) + margin;
    if (glm::dot(nearest, nearest) >= reach * reach) return false;
    const glm::dvec3 highest(n.x >= 0.0 ? hi.x : lo.x, n.y >= 0.0 ? hi.y : lo.y, n.z >= 0.0 ? hi.z : lo.z);
    return glm::dot(n, highest - c) >= -double(b.base) - 1.5 * h - margin;
}

// Calls f(leaf coordinates) for each leaf ball b reaches.
template <typename F>
void forEachLeafReached(const Metaball &b, double h, F f) {
    const openvdb::CoordBBox box = leavesOf(b, h).leaves;
    for (auto it = box.begin(); it; ++it)
        if (reaches(b, *it, h)) f(*it);
}

// Balls from a user's edits may hold anything: every value finite, radius positive, every ball inside the
// index range the leaf keys address, and no single ball (or all of them together) bigger than the budget.
void checkBalls(const std::vector<Metaball> &balls, const RasterSettings &s) {
    const double reach = double(kKeyBias - 2) * kLeafDim * s.voxelSize;  // m from the origin
    double pairs = 0.0;
    for (std::size_t i = 0; i < balls.size(); ++i) {
        const Metaball &b = balls[i];
        const float sum = b.centre.x + b.centre.y + b.centre.z + b.normal.x + b.normal.y + b.normal.z + b.radius +
                          b.base + b.depth;
        if (!std::isfinite(sum) || !(b.radius > 0.0f))
            throw InvalidArgument("metaball " + std::to_string(i) +
                                  " has a non-finite value or a radius that is not positive");
        const float far = std::max({std::abs(b.centre.x), std::abs(b.centre.y), std::abs(b.centre.z)}) + b.radius;
        if (!(far < reach))
            throw InvalidArgument("metaball " + std::to_string(i) + " reaches " + std::to_string(far) +
                                  " m from the origin; at this voxel size the grid ends at " + std::to_string(reach) +
                                  " m");
        const double leaves = double(leavesOf(b, s.voxelSize).leaves.volume());
        checkVoxelBudget(leaves * kLeafVoxels / 4.0, s);  // this ball alone
        pairs += leaves;
    }
    // Deep snow has a few thousand balls reaching each leaf, some 16 per voxel of the budget at most.
    checkVoxelBudget(pairs / 32.0, s);
}

std::string millions(double n) {
    std::ostringstream s;
    s.precision(3);
    s << n / 1e6 << " million";
    return s.str();
}

}  // namespace

void checkVoxelBudget(double voxels, const RasterSettings &s, const char *quantifier) {
    if (voxels <= s.maxVoxels) return;
    const double suggested = s.voxelSize * std::cbrt(voxels / s.maxVoxels) * 1.1;
    std::ostringstream msg;
    msg.precision(3);
    msg << "this snow needs " << quantifier << " " << millions(voxels) << " voxels at voxel size " << s.voxelSize
        << " m, over the budget of " << millions(s.maxVoxels) << ": use a voxel size of at least " << suggested
        << " m (or raise the voxel budget in Firn's preferences)";
    throw BudgetExceeded(msg.str());
}

namespace {

// (leaf key, ball index) pairs, sorted: each leaf's balls in a fixed order, whatever the thread count.
std::vector<std::pair<std::uint64_t, std::uint32_t>> binBallsByLeaf(const std::vector<Metaball> &balls, double h) {
    std::vector<std::size_t> offsets(balls.size() + 1, 0);
    tbb::parallel_for(std::size_t(0), balls.size(), [&](std::size_t i) {
        forEachLeafReached(balls[i], h, [&](const openvdb::Coord &) { ++offsets[i + 1]; });
    });
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs(offsets.back());
    tbb::parallel_for(std::size_t(0), balls.size(), [&](std::size_t i) {
        std::size_t at = offsets[i];
        forEachLeafReached(balls[i], h,
                           [&](const openvdb::Coord &leaf) { pairs[at++] = {leafKey(leaf), std::uint32_t(i)}; });
    });
    tbb::parallel_sort(pairs.begin(), pairs.end());
    return pairs;
}

// What the balls that reach one leaf add up to at its voxels: the field F and its gradient (analytic, so the
// distance to the iso-surface needs no neighbour lookups), and field-weighted averages of the depth below the
// snow's top and of the signed distance to the surface the balls stand on (their tangent planes).
struct LeafField {
    std::array<float, kLeafVoxels> field{};
    std::array<float, kLeafVoxels> gradX{}, gradY{}, gradZ{};  // 1/m, by axis: the gather loop vectorizes
    std::array<float, kLeafVoxels> weightedDepth{};      // m x field
    std::array<float, kLeafVoxels> weightedBelowBase{};  // m x field, positive below the surface
};

// floor or ceil of a voxel coordinate, clamped to [lo, hi] before the conversion to int (NaN gives lo): an edited
// ball's base or normal may put its z-range anywhere (UBSan: float-to-int overflow). As selects (std::max(lo, NaN)
// is lo), so that a row of columns vectorizes.
int clampedIndex(float x, int lo, int hi) { return int(std::min(float(hi), std::max(float(lo), x))); }

// An AVX2 clone picked at load time where the processor has it (GCC/Clang on x86): a leaf column of 8 floats is
// one register. AVX2 alone, without FMA, so both clones round every operation alike and the grids come out
// bit-identical.
#if defined(__GNUC__) && defined(__x86_64__)
#define FIRN_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#else
#define FIRN_AVX2_CLONE
#endif

FIRN_AVX2_CLONE
void gatherLeaf(const openvdb::Coord &origin, const std::uint32_t *ballIds, std::size_t count,
                const std::vector<Metaball> &balls, float h, LeafField &out) {
    const int zLeafLo = origin.z(), zLeafHi = origin.z() + kLeafDim - 1;
    for (std::size_t n = 0; n < count; ++n) {
        const Metaball &b = balls[ballIds[n]];
        const glm::vec3 c = b.centre, normal = b.normal;
        const float r2 = b.radius * b.radius, invR2 = 1.0f / r2;
        // m along the normal: 1.5 voxels below the ball's surface the snow has ended (its level set is +band).
        const float lowest = -b.base - 1.5f * h;
        const int xLo = std::max(origin.x(), int(std::ceil((c.x - b.radius) / h)));
        const int xHi = std::min(origin.x() + kLeafDim - 1, int(std::floor((c.x + b.radius) / h)));
        const int yLo = std::max(origin.y(), int(std::ceil((c.y - b.radius) / h)));
        const int yHi = std::min(origin.y() + kLeafDim - 1, int(std::floor((c.y + b.radius) / h)));
        const bool onBase = normal.z > 0.05f;  // else steep: the base does not cut the columns
        for (int x = xLo; x <= xHi; ++x) {
            const float dx = x * h - c.x;
            // Each of the row's 8 columns at once (one register a quantity): the z-range inside the sphere and
            // not far below the ball's surface, as voxel indices. A column outside the sphere gets an empty range.
            std::array<float, kLeafDim> dyOf, lateralOf;
            std::array<int, kLeafDim> kLoOf, kHiOf;
            for (int j = 0; j < kLeafDim; ++j) {
                const float dy = (origin.y() + j) * h - c.y;
                const float rest = r2 - dx * dx - dy * dy;
                const float half = std::sqrt(std::max(rest, 0.0f));
                const float lateral = normal.x * dx + normal.y * dy;
                const float base = c.z + (lowest - lateral) / normal.z;
                const float zLo = onBase ? std::max(c.z - half, base) : c.z - half;
                const int kLo = clampedIndex(std::ceil(zLo / h), zLeafLo, zLeafHi + 1);
                dyOf[j] = dy, lateralOf[j] = lateral;
                kLoOf[j] = rest > 0.0f ? kLo : zLeafHi + 1;
                kHiOf[j] = clampedIndex(std::floor((c.z + half) / h), zLeafLo - 1, zLeafHi);
            }
            for (int y = yLo; y <= yHi; ++y) {
                const int j = y - origin.y();
                const int kLo = kLoOf[j], kHi = kHiOf[j];
                if (kLo > kHi) continue;
                const float dy = dyOf[j], lateral = lateralOf[j];
                const int row = ((x - origin.x()) << 6) | (j << 3);
                const float dxy2 = dx * dx + dy * dy;
                // The whole column of the leaf, masked to [kLo, kHi]: a fixed, branch-free loop that vectorizes.
                for (int k = 0; k < kLeafDim; ++k) {
                    const int z = zLeafLo + k;
                    const float dz = z * h - c.z;
                    const float u2 = (dxy2 + dz * dz) * invR2;
                    const float height = lateral + normal.z * dz;  // m above the centre along the normal
                    // Nothing outside the ball or below its lowest height.
                    const float reach = float((z >= kLo) & (z <= kHi) & (u2 < 1.0f) & (height >= lowest));
                    const float f = reach * wyvillField(u2);
                    const float slope = reach * 2.0f * wyvillFieldSlope(u2) * invR2;
                    const int i = row + k;
                    out.field[i] += f;
                    out.gradX[i] += slope * dx;
                    out.gradY[i] += slope * dy;
                    out.gradZ[i] += slope * dz;
                    out.weightedDepth[i] += f * (b.depth - height);
                    out.weightedBelowBase[i] += f * (-b.base - height);
                }
            }
        }
    }
}

// Turns one leaf's gathered field into its two output leaves. Snow is where the field exceeds the iso-value
// AND which lies above the surface the balls stand on, so its signed distance is the larger of two: the
// first-order distance to the iso-surface, (iso - F) / |grad F| (exact for a planar field, within a fraction of
// a voxel near the surface), and the distance below the balls' surface (moved half a voxel into the object).
// Clamped to +-band. The density follows
// the compaction profile at the field-weighted depth, times the voxel's coverage by snow: a one-voxel ramp
// centred on the surface, so that Cycles' trilinear density crosses half at the snow's surface.
// `surface` and `density` are new leaves (inactive background): their buffers and masks are written whole.
// Two passes: the distances, coverages and depths of all 512 voxels without a branch (the loop vectorizes, its
// three divisions four at a time), then the masks and the densities of the voxels with snow.
FIRN_AVX2_CLONE
void finishLeaf(const LeafField &in, const RasterSettings &s, FloatLeaf &surface, FloatLeaf &density) {
    const double h = s.voxelSize, band = kSurfaceBandVoxels * h;
    float *distances = surface.buffer().data(), *densities = density.buffer().data();
    std::array<double, kLeafVoxels> coverageOf, depthOf;
    std::array<std::uint8_t, kLeafVoxels> nearOf;
    for (int i = 0; i < kLeafVoxels; ++i) {
        // A voxel no ball reaches (field 0, no gradient) comes out +band: outside, no snow.
        const double field = in.field[i];
        const double gradient = glm::length(glm::vec3(in.gradX[i], in.gradY[i], in.gradZ[i]));
        const double toIso = (kSnowIsoValue - field) / std::max(gradient, 1e-12);
        // Half a voxel into the object, so that the voxel on its surface is whole snow: no thin gap below.
        const double belowBase = field > 0.0 ? in.weightedBelowBase[i] / field - 0.5 * h : band;
        const double clamped = std::clamp(std::max(toIso, belowBase), -band, band);
        // Float sums of absurd (edited) balls overflowed: no snow.
        const double distance = std::isnan(clamped) ? band : clamped;
        distances[i] = float(distance);
        nearOf[i] = std::abs(distance) < band;
        coverageOf[i] = std::clamp(0.5 - distance / h, 0.0, 1.0);
        depthOf[i] = field > 0.0 ? std::max(0.0, in.weightedDepth[i] / field) : 0.0;
    }
    FloatLeaf::NodeMaskType nearSurface, snow;
    for (int i = 0; i < kLeafVoxels; ++i) {
        nearSurface.set(i, nearOf[i]);
        if (coverageOf[i] < 1e-4) continue;  // rounding at the ramp's foot: no snow
        densities[i] = float(coverageOf[i] * s.compaction.density(depthOf[i]));
        snow.setOn(i);
    }
    surface.setValueMask(nearSurface);
    density.setValueMask(snow);
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
    // OpenVDB refuses transforms below ~1.5e-5 m (its determinant tolerance); snow needs no voxel under 0.1 mm.
    if (!(h >= kMinVoxelSize) || !std::isfinite(h))
        throw InvalidArgument("voxel size must be a finite number of metres, at least 0.1 mm (got " + std::to_string(h) + ")");
    checkBalls(balls, s);

    const auto pairs = binBallsByLeaf(balls, h);
    std::vector<std::size_t> starts;  // first pair of each leaf
    for (std::size_t i = 0; i < pairs.size(); ++i)
        if (i == 0 || pairs[i].first != pairs[i - 1].first) starts.push_back(i);
    const double leafVoxels = double(starts.size()) * kLeafVoxels;
    checkVoxelBudget(leafVoxels / 4.0, s);  // leaves are rarely less than a quarter full
    starts.push_back(pairs.size());
    progress.report(0.1);
    progress.throwIfCancelled();

    SnowGrids grids{makeGrid("density", h), makeGrid("surface", h)};
    grids.density->setGridClass(openvdb::GRID_FOG_VOLUME);
    grids.surface->setGridClass(openvdb::GRID_LEVEL_SET);
    grids.surface->tree().root().setBackground(float(kSurfaceBandVoxels * h), false);  // outside every ball
    const std::size_t leafCount = starts.size() - 1;
    std::vector<FloatLeaf *> densityLeaves(leafCount), surfaceLeaves(leafCount);
    for (std::size_t l = 0; l < leafCount; ++l) {
        const openvdb::Coord origin = leafOrigin(pairs[starts[l]].first);
        densityLeaves[l] = grids.density->tree().touchLeaf(origin);
        surfaceLeaves[l] = grids.surface->tree().touchLeaf(origin);
    }
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leafCount, 64), [&](const tbb::blocked_range<std::size_t> &r) {
        progress.throwIfCancelled();
        std::vector<std::uint32_t> ids;
        auto leafField = std::make_unique<LeafField>();
        for (std::size_t l = r.begin(); l != r.end(); ++l) {
            ids.clear();
            for (std::size_t p = starts[l]; p < starts[l + 1]; ++p) ids.push_back(pairs[p].second);
            *leafField = LeafField{};
            gatherLeaf(densityLeaves[l]->origin(), ids.data(), ids.size(), balls, float(h), *leafField);
            finishLeaf(*leafField, s, *surfaceLeaves[l], *densityLeaves[l]);
        }
        progress.report(0.1 + 0.85 * double(done += r.size()) / double(leafCount));
    });
    progress.throwIfCancelled();
    // Inactive voxels of the level set take +-band by their side: tiles deep inside the snow become -band.
    openvdb::tools::pruneLevelSet(grids.surface->tree());
    openvdb::tools::pruneInactive(grids.density->tree());
    grids.density->insertMeta("units", openvdb::StringMetadata("kg/m^3"));
    grids.surface->insertMeta("units", openvdb::StringMetadata("m"));
    progress.report(1.0);
    return grids;
}

LeafBallIndex::LeafBallIndex(const std::vector<Metaball> &balls, double voxelSize) : voxelSize_(voxelSize) {
    for (const auto &[key, id] : binBallsByLeaf(balls, voxelSize)) leaves_[key].push_back(id);
}

void LeafBallIndex::insert(std::uint32_t id, const Metaball &ball) {
    forEachLeafReached(ball, voxelSize_, [&](const openvdb::Coord &leaf) {
        std::vector<std::uint32_t> &ids = leaves_[leafKey(leaf)];
        ids.insert(std::lower_bound(ids.begin(), ids.end(), id), id);
    });
}

void LeafBallIndex::erase(std::uint32_t id, const Metaball &ball) {
    forEachLeafReached(ball, voxelSize_, [&](const openvdb::Coord &leaf) {
        const auto found = leaves_.find(leafKey(leaf));
        if (found == leaves_.end()) return;
        std::vector<std::uint32_t> &ids = found->second;
        const auto at = std::lower_bound(ids.begin(), ids.end(), id);
        if (at != ids.end() && *at == id) ids.erase(at);
        if (ids.empty()) leaves_.erase(found);
    });
}

bool LeafBallIndex::sameLeaves(const Metaball &a, const Metaball &b) const {
    std::vector<openvdb::Coord> leavesA, leavesB;
    leavesOf(a, leavesA), leavesOf(b, leavesB);
    return leavesA == leavesB;
}

void LeafBallIndex::leavesOf(const Metaball &ball, std::vector<openvdb::Coord> &out) const {
    forEachLeafReached(ball, voxelSize_, [&](const openvdb::Coord &leaf) {
        out.emplace_back(leaf.x() * kLeafDim, leaf.y() * kLeafDim, leaf.z() * kLeafDim);
    });
}

const std::vector<std::uint32_t> *LeafBallIndex::ballsOf(const openvdb::Coord &leafOrigin) const {
    const openvdb::Coord leaf(leafOrigin.x() >> 3, leafOrigin.y() >> 3, leafOrigin.z() >> 3);
    const auto found = leaves_.find(leafKey(leaf));
    return found == leaves_.end() ? nullptr : &found->second;
}

void rasterizeLeaves(const std::vector<Metaball> &balls, const LeafBallIndex &index,
                     const std::vector<openvdb::Coord> &leafOrigins, const RasterSettings &s, SnowGrids &grids) {
    const double h = s.voxelSize;
    const float band = float(kSurfaceBandVoxels * h);
    const std::size_t count = leafOrigins.size();
    std::vector<std::unique_ptr<FloatLeaf>> surfaces(count), densities(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4), [&](const tbb::blocked_range<std::size_t> &r) {
        auto leafField = std::make_unique<LeafField>();
        for (std::size_t l = r.begin(); l != r.end(); ++l) {
            const std::vector<std::uint32_t> *ids = index.ballsOf(leafOrigins[l]);
            if (!ids) continue;
            *leafField = LeafField{};
            gatherLeaf(leafOrigins[l], ids->data(), ids->size(), balls, float(h), *leafField);
            surfaces[l] = std::make_unique<FloatLeaf>(leafOrigins[l], band, false);
            densities[l] = std::make_unique<FloatLeaf>(leafOrigins[l], 0.0f, false);
            finishLeaf(*leafField, s, *surfaces[l], *densities[l]);
        }
    });
    // As pruneLevelSet and pruneInactive leave them: a leaf without active voxels is a tile, inside (-band) or
    // outside (+band) by the sign of its first value; an empty density leaf is the background.
    openvdb::FloatTree &surface = grids.surface->tree(), &density = grids.density->tree();
    const auto setTile = [](openvdb::FloatTree &tree, const openvdb::Coord &origin, float value) {
        if (tree.probeConstLeaf(origin) || tree.getValue(origin) != value) tree.addTile(1, origin, value, false);
    };
    for (std::size_t l = 0; l < count; ++l) {
        const openvdb::Coord &origin = leafOrigins[l];
        if (surfaces[l] && !surfaces[l]->isInactive()) {
            surface.addLeaf(surfaces[l].release());
        } else {
            const bool inside = surfaces[l] && surfaces[l]->getFirstValue() < 0.0f;
            setTile(surface, origin, inside ? -band : band);
        }
        if (densities[l] && !densities[l]->isInactive()) density.addLeaf(densities[l].release());
        else setTile(density, origin, 0.0f);
    }
}

}  // namespace firn
