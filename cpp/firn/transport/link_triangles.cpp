#include "firn/transport/link_triangles.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "firn/geometry/box_triangle.h"
#include "firn/transport/snow_topology.h"

namespace firn {

namespace {

// Voxels of pad beyond the rounding: a hit lies on the triangle and the segment to within float rounding of their
// coordinates (the ray's origin rounded to float, Embree's watertight test in float); the pad keeps far outside it.
constexpr double kLinkPadVoxels = 0.01;

// m: how far float rounding may move a point of the ray or of a triangle in a scene reaching `extent` m from the
// origin: 16 units in the last place of the largest coordinate, a wide bound on the origin's rounding and Embree's
// test's error (a few units of the coordinates it subtracts).
double roundingReach(double extent) { return 16.0 * std::numeric_limits<float>::epsilon() * extent; }

}  // namespace

double linkPad(const Medium &medium, const Occluders &occluders) {
    double extent = std::max({glm::length(medium.boundsMin()), glm::length(medium.boundsMax()), 1.0});
    for (const glm::vec3 &p : occluders.mesh().positions) extent = std::max(extent, double(glm::length(p)));
    return kLinkPadVoxels * medium.voxelSize() + roundingReach(extent);
}

LinkTriangles::LinkTriangles(const Medium &medium, const Occluders &occluders, const openvdb::CoordBBox &lowers,
                             double pad)
    : medium_(&medium), pad_(pad) {
    if (occluders.empty()) return;
    // Every link's box: from the first lower voxel's centre to past the last one's upper neighbours, on every axis.
    const glm::dvec3 lo = medium.voxelCentre(lowers.min()) - pad;
    const glm::dvec3 hi = medium.voxelCentre(lowers.max()) + (1.0 + kLinkRayNudge) * medium.voxelSize() + pad;
    const TriangleMesh &mesh = occluders.mesh();
    for (const unsigned t : occluders.caster().trianglesInBox(lo, hi)) {
        const glm::dvec3 a(mesh.vertex(t, 0)), b(mesh.vertex(t, 1)), c(mesh.vertex(t, 2));
        near_.push_back({glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c)), a, b, c});
    }
}

void LinkTriangles::linkBox(const openvdb::Coord &lower, int axis, glm::dvec3 &lo, glm::dvec3 &hi) const {
    const glm::dvec3 p = medium_->voxelCentre(lower);
    lo = p - pad_, hi = p + pad_;
    hi[axis] += (1.0 + kLinkRayNudge) * medium_->voxelSize();
}

bool LinkTriangles::mayCross(const openvdb::Coord &lower, int axis) const {
    glm::dvec3 lo, hi;
    linkBox(lower, axis, lo, hi);
    for (const Near &t : near_) {
        if (t.hi.x < lo.x || t.hi.y < lo.y || t.hi.z < lo.z || t.lo.x > hi.x || t.lo.y > hi.y || t.lo.z > hi.z)
            continue;
        if (triangleOverlapsBox(lo, hi, t.a, t.b, t.c)) return true;
    }
    return false;
}

}  // namespace firn
