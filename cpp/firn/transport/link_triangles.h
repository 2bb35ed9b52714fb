#pragma once

#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/scene.h"

namespace firn {

// m: how far beyond a link's segment LinkTriangles looks: far past the float rounding of the ray's origin and of
// Embree's test in a scene as wide as the medium and the occluders.
double linkPad(const Medium &medium, const Occluders &occluders);

// The occluder triangles near a block of voxels' links, and an exact pre-test of one link against them before
// occluderOnLink's Embree ray (snow_topology.h). The ray meets a triangle only at a point both share, so a link whose
// segment, padded by more than Embree's and the ray origin's rounding, no triangle overlaps has no hit and needs no
// ray: the car's topology cast one per link of every voxel of a leaf near an occluder (9.2 M, 3.4 per active voxel),
// most of them voxels away from any triangle (docs/benchmarks.md, car-links).
class LinkTriangles {
  public:
    // The triangles that may cross a link up any axis from a voxel in `lowers` (index space, closed), each link's
    // segment grown by `pad` (linkPad) each way.
    LinkTriangles(const Medium &medium, const Occluders &occluders, const openvdb::CoordBBox &lowers, double pad);

    bool empty() const { return near_.empty(); }
    // False only where occluderOnLink(medium, occluders, lower, axis) finds no hit; `lower` within the block.
    bool mayCross(const openvdb::Coord &lower, int axis) const;

  private:
    struct Near {
        glm::dvec3 lo, hi;  // m: the triangle's bounding box
        glm::dvec3 a, b, c;
    };
    // m: the box of link (lower, axis)'s ray, from the lower voxel's centre to kLinkRayNudge past the upper's, grown by
    // pad_ each way.
    void linkBox(const openvdb::Coord &lower, int axis, glm::dvec3 &lo, glm::dvec3 &hi) const;

    const Medium *medium_;
    double pad_;  // m
    std::vector<Near> near_;
};

}  // namespace firn
