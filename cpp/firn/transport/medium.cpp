#include "firn/transport/medium.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/Prune.h>

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

// Whether the aligned block of Edge^3 children of a node (an 8^3 leaf's cells, a 16^3 node's leaves) that holds
// `child` (local coordinates) has none on in `mask`. The mask holds child (x, y, z) at bit x Dim^2 + y Dim + z: a
// word holds 64 / Dim rows of z, and the block's cells in each of its words one pattern.
template <int Edge, openvdb::Index Log2Dim>
bool blockClear(const openvdb::util::NodeMask<Log2Dim> &mask, const openvdb::Coord &child) {
    using Word = openvdb::Index64;
    constexpr int kDim = 1 << Log2Dim, kRowsPerWord = 64 / kDim, kRows = Edge < kRowsPerWord ? Edge : kRowsPerWord;
    constexpr Word kPattern = [] {  // the block's cells in a word, at its low corner
        Word rows = 0;
        for (int r = 0; r < kRows; ++r) rows |= ((Word(1) << Edge) - 1) << (r * kDim);
        return rows;
    }();
    const openvdb::Coord low = child & ~(Edge - 1);
    Word on = 0;
    for (int x = low.x(); x < low.x() + Edge; ++x)
        for (int y = low.y(); y < low.y() + Edge; y += kRowsPerWord)
            on |= mask.template getWord<Word>((x * kDim + y) * kDim / 64);
    return !(on & kPattern << (low.y() % kRowsPerWord * kDim + low.z()));
}

// Edge (in children) of the largest aligned block, Edge^3 down to 2^3, that holds `child` and none that is on; 1
// if none does.
template <int Edge, openvdb::Index Log2Dim>
int largestClearBlock(const openvdb::util::NodeMask<Log2Dim> &mask, const openvdb::Coord &child) {
    if constexpr (Edge < 2) return 1;
    else return blockClear<Edge>(mask, child) ? Edge : largestClearBlock<Edge / 2>(mask, child);
}

// Edge (in children) of the largest aligned block of a node's children that holds `child` (local coordinates) and
// none that is on in `mask`: Dim / 2 down to 2; 1 if only the child itself is off; 0 if it is on.
template <openvdb::Index Log2Dim>
int emptyBlockEdge(const openvdb::util::NodeMask<Log2Dim> &mask, const openvdb::Coord &child) {
    if (mask.isOn(openvdb::Index((child.x() << 2 * Log2Dim) + (child.y() << Log2Dim) + child.z()))) return 0;
    return largestClearBlock<(1 << Log2Dim) / 2>(mask, child);
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
    openvdb::tools::pruneInactive(*support_);  // a leaf or node without snow is none: the child masks map the snow
}

int Medium::emptyBlockEdge(const SupportNode *node, const openvdb::Coord &cell) {
    if (!node) return int(SupportNode::DIM / 2);
    if (const SupportLeaf *leaf = node->probeConstLeaf(cell))
        return firn::emptyBlockEdge(leaf->getValueMask(), cell & int(SupportLeaf::DIM - 1));
    const openvdb::Coord child = (cell & int(SupportNode::DIM - 1)) >> int(SupportLeaf::LOG2DIM);
    return int(SupportLeaf::DIM) * firn::emptyBlockEdge(node->getChildMask(), child);
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
    // the bounds, reading the density only in cells that may hold snow, past the cells of a leaf's empty 2^3 or 4^3
    // block in one go, and from a cell in an 8^3 block without any on to where it leaves that block, or the 16^3,
    // 32^3 or 64^3 block around it that has none (the step lattice starts anew there).
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
        const int edge = emptyBlockEdge(cell);
        if (edge == 0) {
            sum += density_.in(cell, p) * dt;
            if (sum > sumLimit) break;
            t += dt;
        } else if (edge < int(SupportLeaf::DIM)) {
            // In a leaf, one step a cell: on past the steps whose midpoints lie in the empty block (a little early,
            // never late: rounding), each counted, t as their own sums reach it.
            const double tOut = blockExit(ray, cell, edge) - 1e-6;
            for (t += dt; t < tLast && t + 0.5 * std::min(kLongStep, tLast - t) < tOut;) {
                ++columnSteps_;
                t += std::min(kLongStep, tLast - t);
            }
        } else {
            const double next = std::max(t + 0.5 * dt, blockExit(ray, cell, edge));
            if (!(next > t)) break;  // a last step too short to move t
            t = next;
        }
    }
    return sum * h;
}

int Medium::ColumnMarcher::lastEmptySample(const openvdb::math::Ray<double> &ray, const Vec3d &p, double t0, double dt,
                                           int i, int steps) {
    const openvdb::Coord cell = floorCoord(p);
    const int edge = emptyBlockEdge(cell);
    if (edge == 0) return i - 1;
    if (edge == 1) return i;
    // The samples before the ray leaves the block (a little early, never late: rounding).
    const double last = std::min((blockExit(ray, cell, edge) - t0) / dt - 0.5 - 1e-6, double(steps));
    return std::max(i, int(std::ceil(last)) - 1);
}

}  // namespace firn
