#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/medium.h"
#include "firn/progress.h"
#include "firn/scene.h"

namespace firn {

// The six voxel faces, in the order -x, +x, -y, +y, -z, +z.
inline const openvdb::Coord &faceStep(int face) {
    static const openvdb::Coord kStep[6] = {openvdb::Coord(-1, 0, 0), openvdb::Coord(1, 0, 0),
                                            openvdb::Coord(0, -1, 0), openvdb::Coord(0, 1, 0),
                                            openvdb::Coord(0, 0, -1), openvdb::Coord(0, 0, 1)};
    return kStep[face];
}
inline glm::dvec3 faceNormal(int face) {
    glm::dvec3 n(0.0);
    n[face / 2] = (face & 1) ? 1.0 : -1.0;
    return n;
}

// A face of a snow voxel where the snow ends: open air, or an occluder between the voxel's centre and
// its neighbour's (the ground under the snow).
struct BoundaryFace {
    std::uint32_t voxel = 0;  // index into SnowTopology's voxels
    std::uint8_t face = 0;    // 0..5 as in faceStep
    bool occluder = false;
    float distance = 0.0f;    // occluder faces: m from the voxel centre to the surface
    std::uint32_t triangle = 0;
};

// The unknowns of the diffusion solve: voxels optically thick enough for diffusion (sigma_t h >= 0.1),
// indexed 0..n-1 in OpenVDB leaf order, each linked to its six neighbours or to a boundary face.
struct SnowTopology {
    openvdb::Int32Tree::Ptr index;  // voxel -> unknown, -1 elsewhere
    std::vector<openvdb::Coord> coord;
    std::vector<float> density;                     // kg/m^3
    std::vector<std::array<std::int32_t, 6>> link;  // >= 0: neighbour unknown; < 0: face -1 - link
    std::vector<BoundaryFace> faces;

    std::size_t size() const { return coord.size(); }
    static bool isFace(std::int32_t link) { return link < 0; }
    static std::size_t faceIndex(std::int32_t link) { return std::size_t(-1 - link); }
};

// Voxels with sigma_t h below this are too thin for diffusion: light crosses them (single scattering).
constexpr double kMinVoxelOpticalDepth = 0.1;

SnowTopology buildSnowTopology(const Medium &medium, const Occluders &occluders, const SubProgress &progress);

}  // namespace firn
