#include "firn/transport/medium.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Morphology.h>

#include "firn/util/error.h"
#include "firn/util/openvdb_library.h"

namespace firn {

namespace {

using openvdb::Vec3d;

constexpr double kMaxDensity = 10000.0;              // kg/m^3: ten times ice, room for any scaled grid
constexpr double kMaxVoxelOpticalThickness = 1e7;   // snow at 1 m voxels is ~1e4

// Voxel size if the transform is a uniform scale plus translation (voxel axes = world axes), else 0.
double axisAlignedVoxelSize(const openvdb::math::Transform &transform) {
    if (!transform.isLinear() || !transform.hasUniformScale()) return 0.0;
    const double h = transform.voxelSize()[0];
    const Vec3d o = transform.indexToWorld(Vec3d(0.0));
    for (int axis = 0; axis < 3; ++axis) {
        Vec3d e(0.0);
        e[axis] = 1.0;
        const Vec3d step = transform.indexToWorld(e) - o;
        for (int k = 0; k < 3; ++k)
            if (std::abs(step[k] - (k == axis ? h : 0.0)) > 1e-9 * h) return 0.0;
    }
    return h;
}

// Ray parameter (index space) where the ray leaves the aligned block of dim^3 cells holding `cell`.
double blockExit(const openvdb::math::Ray<double> &ray, const openvdb::Coord &cell, int dim) {
    double exit = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (ray.dir()[a] == 0.0) continue;
        const int origin = cell[a] & ~(dim - 1);
        exit = std::min(exit, ((ray.dir()[a] > 0.0 ? origin + dim : origin) - ray.eye()[a]) * ray.invDir()[a]);
    }
    return exit;
}

// Edge (cells) of the largest aligned block holding `cell` in which no cell of the 8^3 `leaf`'s mask is on:
// 4 or 2; 1 if only the cell itself is off, 0 if it is on. The mask's word x holds the 8x8 cells of slice x,
// bit 8 y + z (OpenVDB's leaf offset 64 x + 8 y + z).
int emptyBlockEdge(const openvdb::util::NodeMask<3> &mask, const openvdb::Coord &cell) {
    using Word = openvdb::Index64;
    const int x = cell.x() & 7, y = cell.y() & 7, z = cell.z() & 7;
    if (mask.getWord<Word>(x) >> (8 * y + z) & 1) return 0;
    const int x4 = x & 4, shift4 = 8 * (y & 4) + (z & 4);
    const Word slices4 = mask.getWord<Word>(x4) | mask.getWord<Word>(x4 + 1) | mask.getWord<Word>(x4 + 2) |
                         mask.getWord<Word>(x4 + 3);
    if (!(slices4 & (Word(0x0F0F0F0F) << shift4))) return 4;
    const int x2 = x & 6, shift2 = 8 * (y & 6) + (z & 6);
    if (!((mask.getWord<Word>(x2) | mask.getWord<Word>(x2 + 1)) & (Word(0x0303) << shift2))) return 2;
    return 1;
}

}  // namespace

Medium::Medium(openvdb::FloatGrid::ConstPtr density, const VolumeOptics &optics)
    : density_(std::move(density)), optics_(optics) {
    initializeOpenVdb();
    validate(optics_);
    if (optics_.extinctionPerDensity <= 0.0) throw InvalidArgument("extinction per density must be positive to bake");
    if (!density_) throw InvalidArgument("no density grid");
    if (density_->background() != 0.0f) throw InvalidArgument("the density grid's background must be 0");
    h_ = axisAlignedVoxelSize(density_->transform());
    if (!(h_ > 0.0)) throw InvalidArgument("the density grid needs cubic voxels aligned with the world axes");
    if (density_->tree().activeTileCount() > 0) {  // Cycles draws tiles as nothing; light sees voxels only
        auto voxels = density_->deepCopy();
        voxels->tree().voxelizeActiveTiles();
        density_ = voxels;
    }
    if (density_->activeVoxelCount() == 0) throw InvalidArgument("the density grid has no active voxels");
    const Vec3d o = density_->transform().indexToWorld(Vec3d(0.0));
    origin_ = glm::dvec3(o.x(), o.y(), o.z());

    for (auto it = density_->cbeginValueOn(); it; ++it) {
        const float v = *it;
        if (!std::isfinite(v) || v < 0.0f)
            throw InvalidArgument("density must be finite and non-negative (kg/m^3), found " + std::to_string(v));
        maxDensity_ = std::max(maxDensity_, double(v));
    }
    // Beyond these no snow exists and the solver's arithmetic degrades (a coarse operator that is no longer
    // positive definite at 1e30 m^2/kg): refuse them with the numbers, not a solver failure.
    if (maxDensity_ > kMaxDensity)
        throw InvalidArgument("density above 10000 kg/m^3 is not snow (ice is 917), found " +
                              std::to_string(maxDensity_));
    if (!(maxSigmaT() * h_ <= kMaxVoxelOpticalThickness))
        throw InvalidArgument("a voxel " + std::to_string(h_) + " m wide is " + std::to_string(maxSigmaT() * h_) +
                              " mean free paths thick (extinction per density x density x voxel size); at most 1e7");
    // Inactive voxels inside leaves may hold values other than the background: trilinear lookups read them.
    for (auto leaf = density_->tree().cbeginLeaf(); leaf; ++leaf)
        for (auto it = leaf->cbeginValueOff(); it; ++it)
            if (*it != 0.0f) throw InvalidArgument("inactive density voxels must hold 0");

    const openvdb::CoordBBox box = density_->evalActiveVoxelBoundingBox();
    boundsMin_ = indexToWorld(glm::dvec3(box.min().x() - 1, box.min().y() - 1, box.min().z() - 1));
    boundsMax_ = indexToWorld(glm::dvec3(box.max().x() + 1, box.max().y() + 1, box.max().z() + 1));
    // Three face-dilations reach every voxel whose trilinear cell touches an active voxel (corners included).
    intersector_ = std::make_unique<openvdb::tools::VolumeRayIntersector<openvdb::FloatGrid, 0>>(*density_, 3);
    support_ = std::make_shared<openvdb::BoolTree>(density_->tree(), false, openvdb::TopologyCopy());
    openvdb::tools::dilateActiveValues(*support_, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    markOccupiedBlocks();
}

void Medium::markOccupiedBlocks() {
    openvdb::CoordBBox box;
    support_->evalLeafBoundingBox(box);
    blocksOrigin_ = box.min() & ~(kBlockEdges[2] - 1);
    for (int level = 0; level < 3; ++level) {
        const openvdb::Coord &n = blockCounts_[level] =
            ((box.max() - blocksOrigin_) >> kBlockLog2[level]) + openvdb::Coord(1);
        blockOccupied_[level].assign(std::size_t(n.x()) * n.y() * n.z(), 0);
        for (auto leaf = support_->cbeginLeaf(); leaf; ++leaf) {
            if (leaf->isEmpty()) continue;
            const openvdb::Coord b = (leaf->origin() - blocksOrigin_) >> kBlockLog2[level];  // holds the whole leaf
            blockOccupied_[level][(std::size_t(b.x()) * n.y() + b.y()) * n.z() + b.z()] = 1;
        }
    }
}

int Medium::clearBlockEdge(const openvdb::Coord &cell) const {
    for (int level = 2; level >= 0; --level) {
        const openvdb::Coord b = (cell - blocksOrigin_) >> kBlockLog2[level];
        const openvdb::Coord &n = blockCounts_[level];
        if (b.x() < 0 || b.y() < 0 || b.z() < 0 || b.x() >= n.x() || b.y() >= n.y() || b.z() >= n.z())
            return kBlockEdges[level];  // beyond the support's box
        if (!blockOccupied_[level][(std::size_t(b.x()) * n.y() + b.y()) * n.z() + b.z()]) return kBlockEdges[level];
    }
    return 0;
}

int Medium::emptyBlockEdge(const openvdb::Coord &cell, SupportAccessor &support) const {
    if (const int edge = clearBlockEdge(cell)) return edge;
    const openvdb::BoolTree::LeafNodeType *leaf = support.probeConstLeaf(cell);
    return leaf ? firn::emptyBlockEdge(leaf->getValueMask(), cell) : int(openvdb::BoolTree::LeafNodeType::DIM);
}

Medium::~Medium() = default;

bool Medium::clipToBounds(const glm::dvec3 &origin, const glm::dvec3 &direction, double &t0, double &t1) const {
    t0 = 0.0;
    t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (direction[a] == 0.0) {
            if (origin[a] < boundsMin_[a] || origin[a] > boundsMax_[a]) return false;
            continue;
        }
        double ta = (boundsMin_[a] - origin[a]) / direction[a];
        double tb = (boundsMax_[a] - origin[a]) / direction[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 < t1;
}

double Medium::densityAt(const glm::dvec3 &world, Accessor &accessor) const {
    const glm::dvec3 ijk = worldToIndex(world);
    return openvdb::tools::BoxSampler::sample(accessor, Vec3d(ijk.x, ijk.y, ijk.z));
}

Medium::DensitySampler::DensitySampler(const Medium &medium) : accessor_(medium.accessor()), cell_(0) {
    openvdb::tools::BoxSampler::getValues(corners_, accessor_, cell_);
}

Medium::ColumnMarcher::ColumnMarcher(const Medium &medium)
    : medium_(medium), intersector_(*medium.intersector_), density_(medium), support_(*medium.support_) {}

double Medium::ColumnMarcher::column(const glm::dvec3 &origin, const glm::dvec3 &direction, double tMax,
                                     double limit) {
    const double h = medium_.voxelSize();
    const glm::dvec3 start = medium_.worldToIndex(origin);
    const Vec3d eye(start.x, start.y, start.z), dir(direction.x, direction.y, direction.z);
    constexpr double kStep = 0.5;  // voxels
    const double sumLimit = limit / h, tEnd = tMax / h;
    // Most rays start in snow and reach the limit within a few voxels: plain steps first; the walk below only
    // for rays that get further.
    // A ray that meets empty space (it started outside, or left the snow) goes over to the walk at once.
    constexpr int kPlainSteps = 16;
    double sum = 0.0;  // kg/m^3 * voxels
    int i = 0;
    for (; i < kPlainSteps; ++i) {
        const double t = (i + 0.5) * kStep;
        if (t >= tEnd) return sum * h;
        ++columnSteps_;
        const double rho = densityAt(eye + t * dir);
        if (rho <= 0.0) break;
        sum += rho * kStep;
        if (sum > sumLimit) return sum * h;
    }
    // Beyond the first voxels a ray mostly crosses air near the surface: whole-voxel steps up to where it leaves
    // the bounds, reading the density only in cells that may hold snow, and from a cell in an 8^3 block without
    // any on to where it leaves that block, or the 16^3, 32^3 or 64^3 block around it that has none.
    const openvdb::math::Ray<double> ray(eye, dir);
    constexpr double kLongStep = 1.0;  // voxels
    double tBoundsIn = 0.0, tBoundsOut = 0.0;
    if (!medium_.clipToBounds(origin, direction, tBoundsIn, tBoundsOut)) return sum * h;
    const double tLast = std::min(tMax, tBoundsOut) / h;  // no snow beyond (index space)
    for (double t = i * kStep; t < tLast;) {
        ++columnSteps_;
        const double dt = std::min(kLongStep, tLast - t);
        const Vec3d p = ray(t + 0.5 * dt);
        const openvdb::Coord cell = floorCoord(p);
        if (const SupportLeaf *leaf = supportLeaf(cell)) {
            if (leaf->isValueOn(cell)) {
                sum += density_.in(cell, p) * dt;
                if (sum > sumLimit) break;
            }
            t += dt;
            continue;
        }
        const int edge = std::max(medium_.clearBlockEdge(cell), int(openvdb::BoolTree::LeafNodeType::DIM));
        const double next = std::max(t + 0.5 * dt, blockExit(ray, cell, edge));
        if (!(next > t)) break;  // a last step too short to move t
        t = next;
    }
    return sum * h;
}

int Medium::ColumnMarcher::lastEmptySample(const openvdb::math::Ray<double> &ray, const Vec3d &p, double t0, double dt,
                                           int i, int steps) {
    const openvdb::Coord cell = floorCoord(p);
    const SupportLeaf *leaf = supportLeaf(cell);
    const int edge = leaf ? firn::emptyBlockEdge(leaf->getValueMask(), cell) : int(SupportLeaf::DIM);
    if (edge == 0) return i - 1;
    if (edge == 1) return i;
    // The samples before the ray leaves the block (a little early, never late: rounding).
    const double last = std::min((blockExit(ray, cell, edge) - t0) / dt - 0.5 - 1e-6, double(steps));
    return std::max(i, int(std::ceil(last)) - 1);
}

}  // namespace firn
