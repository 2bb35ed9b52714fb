#include "firn/spray/tracks.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <tbb/parallel_for.h>

#include "firn/util/ceil_count.h"
#include "firn/util/error.h"

namespace firn {

namespace {

constexpr double kBandVoxels = 3.0;        // the snow surface's half band (snow/snow_rasterizer.cpp)
constexpr int kMaxBoxesBetween = 256;      // positions added between two given ones, at most
constexpr double kMinUpwardNormal = 0.25;  // cos of the steepest normal a box is raised along in full

using openvdb::Vec3s;

// Every snow voxel's world box, in the level set's active voxels and interior tiles: its top along `up` (m).
double snowTop(const openvdb::FloatGrid &surface, const glm::dvec3 &up) {
    const openvdb::CoordBBox box = surface.evalActiveVoxelBoundingBox();
    double top = -std::numeric_limits<double>::infinity();
    for (int corner = 0; corner < 8; ++corner) {
        const openvdb::Coord c((corner & 1) ? box.max().x() : box.min().x(), (corner & 2) ? box.max().y() : box.min().y(),
                               (corner & 4) ? box.max().z() : box.min().z());
        const openvdb::Vec3d w = surface.indexToWorld(c);
        top = std::max(top, glm::dot(glm::dvec3(w.x(), w.y(), w.z()), up));
    }
    return top;
}

// The rectangles given, with more between consecutive ones wherever a corner moves more than half `narrowest`.
std::vector<EmitterRectangle> densify(const std::vector<EmitterRectangle> &given, double thickness) {
    std::vector<EmitterRectangle> out;
    for (std::size_t i = 0; i < given.size(); ++i) {
        if (i > 0) {
            const EmitterRectangle &a = given[i - 1], &b = given[i];
            const auto ca = a.corners(), cb = b.corners();
            double moved = 0.0;
            for (int k = 0; k < 4; ++k) moved = std::max(moved, glm::length(cb[k] - ca[k]));
            const double narrowest = std::min({2.0 * glm::length(a.halfU), 2.0 * glm::length(a.halfV), thickness});
            const int n = ceilCount(moved / (0.5 * narrowest), kMaxBoxesBetween);
            const Emitter pair{{a, b}};
            for (int k = 1; k < n; ++k) out.push_back(emitterBetween(pair, 0, double(k) / n));
        }
        out.push_back(given[i]);
    }
    return out;
}

// A rectangle's upward normal (the side away from `down`).
glm::dvec3 upwardNormal(const EmitterRectangle &r, const glm::dvec3 &up) {
    const glm::dvec3 n = glm::normalize(glm::cross(r.halfU, r.halfV));
    return glm::dot(n, up) < 0.0 ? -n : n;
}

// How far (m) along its upward normal n a rectangle rises to `top` along `up`: a vertical rectangle no higher than
// 1 / kMinUpwardNormal times the height it needs.
double verticalRaise(const EmitterRectangle &r, const glm::dvec3 &n, const glm::dvec3 &up, double top) {
    double lowest = std::numeric_limits<double>::infinity();
    for (const glm::dvec3 &p : r.corners()) lowest = std::min(lowest, glm::dot(p, up));
    return std::max(0.0, top - lowest) / std::max(glm::dot(n, up), kMinUpwardNormal);
}

// The eight corners of one position's box: the rectangle lowered by `thickness` and raised by `raise` (m) along its
// upward normal n.
std::array<Vec3s, 8> boxCorners(const EmitterRectangle &r, const glm::dvec3 &n, double thickness, double raise) {
    const auto c = r.corners();
    std::array<Vec3s, 8> out;
    for (int k = 0; k < 4; ++k) {
        const glm::dvec3 bottom = c[k] - thickness * n, upper = c[k] + (raise + thickness) * n;
        out[k] = Vec3s(float(bottom.x), float(bottom.y), float(bottom.z));
        out[k + 4] = Vec3s(float(upper.x), float(upper.y), float(upper.z));
    }
    return out;
}

openvdb::BBoxd boundsOf(const std::array<Vec3s, 8> &corners) {
    openvdb::BBoxd box;
    for (const Vec3s &p : corners) box.expand(openvdb::Vec3d(p));
    return box;
}

using SurfaceLeaf = openvdb::FloatTree::LeafNodeType;

// The surface's leaves and its linear index frame (world = origin + M ijk, so a world dot product d . x is
// d_ijk . M^T x), made once for all of a track's boxes.
struct SurfaceIndex {
    const openvdb::FloatGrid &surface;
    std::vector<const SurfaceLeaf *> leaves;
    glm::dvec3 origin;
    glm::dmat3 Mt;  // M^T

    explicit SurfaceIndex(const openvdb::FloatGrid &grid) : surface(grid) {
        for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) leaves.push_back(leaf.getLeaf());
        const auto world = [&](const openvdb::Vec3d &ijk) {
            const openvdb::Vec3d w = grid.indexToWorld(ijk);
            return glm::dvec3(w.x(), w.y(), w.z());
        };
        origin = world(openvdb::Vec3d(0.0));
        glm::dmat3 M;
        for (int k = 0; k < 3; ++k) M[k] = world(openvdb::Vec3d(k == 0, k == 1, k == 2)) - origin;
        Mt = glm::transpose(M);
    }
};

// The snow over a position: its highest point above the rectangle's plane (m along the upward normal) and along up.
struct SnowOver {
    double aboveRectangle = -std::numeric_limits<double>::infinity(), top = -std::numeric_limits<double>::infinity();
};

// The surface's active voxels within `margin` (m) of the prism a rectangle sweeps along its upward
// normal n from `thickness` under it, inside `column` (world); none where it holds none. On a slope a box rises
// above the snow over it, not above the slope's top: a ski 2 m down a 20 degree slope, raised to the top, cut
// boxes 0.7 m tall, and the frame's track took 4x the time.
std::optional<SnowOver> snowOver(const SurfaceIndex &index, const EmitterRectangle &r, const glm::dvec3 &n,
                                 const glm::dvec3 &up, double thickness, double margin, const openvdb::BBoxd &column) {
    // Dual basis of (halfU, halfV) in the rectangle's plane: s = d . a, t = d . b; a unit step moves s by |a|.
    const glm::dvec3 a = glm::cross(r.halfV, n) / glm::dot(r.halfU, glm::cross(r.halfV, n));
    const glm::dvec3 b = glm::cross(n, r.halfU) / glm::dot(r.halfV, glm::cross(n, r.halfU));
    const double sMax = 1.0 + margin * glm::length(a), tMax = 1.0 + margin * glm::length(b);
    const double bottom = -thickness - margin;
    const openvdb::FloatGrid &surface = index.surface;
    const glm::dvec3 aI = index.Mt * a, bI = index.Mt * b, nI = index.Mt * n, upI = index.Mt * up;
    const openvdb::Vec3d c = surface.worldToIndex(openvdb::Vec3d(r.centre.x, r.centre.y, r.centre.z));
    const glm::dvec3 cI(c.x(), c.y(), c.z());
    const double leafRadius = 0.5 * std::sqrt(3.0) * (SurfaceLeaf::DIM - 1);  // centre to corner voxel, index units
    const openvdb::CoordBBox within = surface.transform().worldToIndexNodeCentered(column);
    std::optional<SnowOver> over;
    for (const SurfaceLeaf *leaf : index.leaves) {
        if (!leaf->getNodeBoundingBox().hasOverlap(within)) continue;
        const glm::dvec3 mid = glm::dvec3(leaf->origin().x(), leaf->origin().y(), leaf->origin().z()) +
                               0.5 * (SurfaceLeaf::DIM - 1) - cI;
        if (std::abs(glm::dot(mid, aI)) > sMax + leafRadius * glm::length(aI) ||
            std::abs(glm::dot(mid, bI)) > tMax + leafRadius * glm::length(bI) ||
            glm::dot(mid, nI) < bottom - leafRadius * glm::length(nI))
            continue;  // no voxel of this leaf within reach
        for (auto v = leaf->cbeginValueOn(); v; ++v) {
            const glm::dvec3 ijk(v.getCoord().x(), v.getCoord().y(), v.getCoord().z()), d = ijk - cI;
            const double above = glm::dot(d, nI);
            if (std::abs(glm::dot(d, aI)) > sMax || std::abs(glm::dot(d, bI)) > tMax || above < bottom) continue;
            if (!over) over = SnowOver{};
            over->aboveRectangle = std::max(over->aboveRectangle, above);
            over->top = std::max(over->top, glm::dot(index.origin, up) + glm::dot(ijk, upI));
        }
    }
    return over;
}

// Signed distance (m) to the union of the boxes, interior filled, exterior band `exteriorVoxels` wide; nullptr when
// no box meets the snow. Throws BudgetExceeded, before allocating, when it could take more than maxVoxels voxels.
openvdb::FloatGrid::Ptr sweptVolume(const std::vector<EmitterRectangle> &positions, const openvdb::FloatGrid &surface,
                                    const glm::dvec3 &up, double thickness, double exteriorVoxels, double maxVoxels) {
    const double h = surface.voxelSize()[0], band = kBandVoxels * h, margin = exteriorVoxels * h;
    const double top = snowTop(surface, up) + band;
    const openvdb::BBoxd snowBox = surface.transform().indexToWorld(surface.evalActiveVoxelBoundingBox());
    const SurfaceIndex index(surface);
    // Each position's box, raised above the snow over it; none where no snow is within reach.
    const std::vector<EmitterRectangle> rectangles = densify(positions, thickness);
    std::vector<std::optional<std::array<Vec3s, 8>>> boxes(rectangles.size());
    tbb::parallel_for(std::size_t(0), rectangles.size(), [&](std::size_t i) {
        const EmitterRectangle &r = rectangles[i];
        const glm::dvec3 n = upwardNormal(r, up);
        if (!std::isfinite(glm::dot(n, n))) return;  // no area (turned half round between positions): sweeps nothing
        openvdb::BBoxd column = boundsOf(boxCorners(r, n, thickness, verticalRaise(r, n, up, top)));
        if (!column.hasOverlap(snowBox)) return;  // the emitter is away from the snow
        column.expand(margin);
        const std::optional<SnowOver> over = snowOver(index, r, n, up, thickness, margin, column);
        if (!over) return;
        // A band over the snow within the swept field's reach of the box: the field there is the tall box's.
        const double raise =
            std::min(std::max(0.0, over->aboveRectangle + band), verticalRaise(r, n, up, over->top + band));
        boxes[i] = boxCorners(r, n, thickness, raise);
    });
    std::vector<Vec3s> points;
    std::vector<openvdb::Vec4I> quads;
    // Corners 0-3 the lowered rectangle, 4-7 the raised one, both counter-clockwise seen from above.
    const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    for (const auto &corners : boxes) {
        if (!corners) continue;
        const unsigned base = unsigned(points.size());
        points.insert(points.end(), corners->begin(), corners->end());
        for (const auto &f : faces) quads.emplace_back(base + f[0], base + f[1], base + f[2], base + f[3]);
    }
    if (quads.empty()) return nullptr;
    // Its voxels are within the boxes' bounds grown by the exterior band: the whole boxes, filled, also where they
    // reach beyond the snow (an emitter far under the snow raises a box up to the snow over it; counted within the
    // snow's bounds alone, such a box passed the budget and took every byte the machine had).
    openvdb::BBoxd bounds;
    for (const Vec3s &p : points) bounds.expand(openvdb::Vec3d(p));
    const openvdb::BBoxd reach(bounds.min() - openvdb::Vec3d(margin), bounds.max() + openvdb::Vec3d(margin));
    const double voxels = reach.volume() / std::pow(h, 3);
    if (voxels > maxVoxels)
        throw BudgetExceeded("an emitter's track over one frame would take about " + std::to_string(voxels) +
                             " voxels, over the budget of " + std::to_string(maxVoxels) +
                             ": use coarser snow voxels, a smaller emitter, or raise the voxel budget");
    return openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(
        surface.transform(), points, {}, quads, float(exteriorVoxels), std::numeric_limits<float>::max());
}

}  // namespace

void TrackSettings::validate() const {
    const auto check = [](bool ok, const char *what) {
        if (!ok) throw InvalidArgument(std::string("spray track settings: ") + what);
    };
    check(thickness > 1e-4 && thickness < 10.0, "thickness must be between 0.1 mm and 10 m");
    check(compactionDepth >= 0.0 && compactionDepth < 10.0, "compaction depth must be between 0 and 10 m");
    check(maxDensity > 0.0 && maxDensity <= 917.0, "the compacted density must be between 0 and 917 kg/m^3");
}

TrackStats carveTrack(SnowGrids &snow, const std::vector<EmitterRectangle> &positions, const glm::dvec3 &down,
                      const TrackSettings &s, double maxVoxels) {
    TrackStats stats;
    if (positions.empty() || snow.surface->activeVoxelCount() == 0) return stats;
    const double h = snow.surface->voxelSize()[0], band = kBandVoxels * h, cube = h * h * h;
    const glm::dvec3 up = -down;
    const openvdb::FloatGrid::Ptr swept =
        sweptVolume(positions, *snow.surface, up, s.thickness, std::max(kBandVoxels, s.compactionDepth / h + 2.0),
                    maxVoxels);
    if (!swept) return stats;

    auto phi = snow.surface->getAccessor();
    auto rho = snow.density->getAccessor();
    // The difference: max(phi, -phi_swept), and the density of the covered part of each voxel removed.
    for (auto it = swept->cbeginValueOn(); it; ++it) {
        const double inSwept = *it;  // m, negative inside the swept volume
        if (inSwept >= band) continue;
        const openvdb::Coord ijk = it.getCoord();
        const float before = phi.getValue(ijk), after = float(std::max(double(before), -inSwept));
        bool changed = false;
        if (after != before) {
            if (after >= band) phi.setValueOff(ijk, float(band));
            else phi.setValue(ijk, after);
            changed = true;
        }
        const double covered = std::clamp(0.5 - inSwept / h, 0.0, 1.0);  // fraction of the voxel swept
        const float density = rho.getValue(ijk);
        if (covered > 0.0 && density > 0.0f) {
            const float left = float(density * (1.0 - covered));
            stats.removedMass += (double(density) - left) * cube;
            if (left > 0.0f) rho.setValue(ijk, left);
            else rho.setValueOff(ijk, 0.0f);
            changed = true;
        }
        stats.carvedVoxels += changed;
    }
    // The layer under the track: snow voxels within compactionDepth of the swept volume whose nearest swept point
    // is straight above (one voxel further up than their distance lies inside it).
    std::vector<openvdb::Coord> layer;
    if (s.compactionDepth > 0.0 && stats.removedMass > 0.0) {
        const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sample(*swept);
        for (auto it = swept->cbeginValueOn(); it; ++it) {
            const double distance = *it;
            if (distance < 0.5 * h || distance > s.compactionDepth + 0.5 * h) continue;
            if (!(rho.getValue(it.getCoord()) > 0.0f)) continue;
            const openvdb::Vec3d w = swept->indexToWorld(it.getCoord());
            const glm::dvec3 above = glm::dvec3(w.x(), w.y(), w.z()) + (distance + h) * up;
            if (sample.wsSample(openvdb::Vec3d(above.x, above.y, above.z)) < 0.0) layer.push_back(it.getCoord());
        }
    }
    if (!layer.empty()) {
        const float added = float(stats.removedMass / (double(layer.size()) * cube));  // kg/m^3 each
        for (const openvdb::Coord &ijk : layer) {
            const float before = rho.getValue(ijk), after = std::min(before + added, float(s.maxDensity));
            rho.setValue(ijk, after);
            stats.compactedMass += double(after - before) * cube;
        }
    }
    if (stats.carvedVoxels > 0) {
        openvdb::tools::pruneLevelSet(snow.surface->tree());
        openvdb::tools::pruneInactive(snow.density->tree());
    }
    return stats;
}

}  // namespace firn
