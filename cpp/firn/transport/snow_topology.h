#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/scene.h"
#include "firn/transport/voxel_links.h"
#include "firn/util/progress.h"
#include "firn/util/unwritten_vector.h"

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
// The face of a voxel against the largest component of a surface's outward normal n: its neighbour there is the snow
// beneath the surface.
inline int faceBeneath(const glm::dvec3 &n) {
    const int axis = std::abs(n.x) >= std::max(std::abs(n.y), std::abs(n.z)) ? 0
                     : std::abs(n.y) >= std::abs(n.z)                        ? 1
                                                                             : 2;
    return 2 * axis + (n[axis] > 0.0 ? 0 : 1);
}

// A face of a snow voxel where the snow ends: open air, or an occluder between the voxel's centre and
// its neighbour's (the ground under the snow).
struct BoundaryFace {
    std::uint32_t voxel = 0;  // index into SnowTopology's voxels
    std::uint8_t face = 0;    // 0..5 as in faceStep
    bool occluder = false;
    float distance = 0.0f;    // occluder faces: m from the voxel centre to the surface
    std::uint32_t triangle = 0;
    float rampMass = 0.0f;    // air faces: kg/m^2 of snow from the voxel centre out to where the density ramps to 0
};

// The smooth surface through a surface voxel (one with air faces): outward normal from the density
// gradient, and the area of that surface inside the voxel (its air faces projected onto it, m^2).
// Light enters and leaves the snow through these patches rather than through the voxels' staircase.
// A voxel on a sharp edge or corner between flat faces (a box's, a layer's cut side) is `sharp`: no smooth
// surface passes through it, and light enters and leaves through each of its air faces on its own (area:
// the faces', share: equal).
struct SurfacePatch {
    glm::dvec3 normal{0.0, 0.0, 1.0};
    double area = 0.0;  // 0 for voxels inside the snow
    std::array<float, 6> share{};  // of the patch's light crossing each air face (sums to 1)
    bool sharp = false;
    double curvature = 0.0;  // per voxel, positive convex (surfaceCurvature); 0 inside the snow
    bool isSurface() const { return area > 0.0; }
    // Whether light travelling against w enters the snow here: through the smooth surface, or at a sharp
    // edge through any of its air faces (then through the one most open to it).
    bool facesTowards(const glm::dvec3 &w) const {
        if (!sharp) return glm::dot(normal, w) > 0.0;
        const int f = airFaceMostOpenTo(w);
        return f >= 0 && glm::dot(faceNormal(f), w) > 0.0;
    }
    // The air face (0..5 as in faceStep) most open to light travelling against w, of the largest n_f . w (the first
    // of equals), -1 where there is none: a sharp voxel's light enters by it (patchOutsideAlong).
    int airFaceMostOpenTo(const glm::dvec3 &w) const {
        int most = -1;
        double open = 0.0;  // n . w of face `most`
        for (int f = 0; f < 6; ++f)
            if (const double c = glm::dot(faceNormal(f), w); share[f] > 0.0f && (most < 0 || c > open))
                most = f, open = c;
        return most;
    }
};

// Values that only surface voxels have (their patch, the light arriving on it from outside), stored for them
// alone (a fifth of the unknowns or fewer) and read by unknown index: other unknowns read `inside`.
template <typename T>
class SurfaceValues {
  public:
    SurfaceValues() = default;
    // slot: per unknown, its surface voxel's index or -1 (SnowTopology::surfaceSlot).
    SurfaceValues(std::shared_ptr<const std::vector<std::int32_t>> slot, std::size_t surfaceVoxels, const T &inside = T{})
        : slot_(std::move(slot)), inside_(inside) {
        parallelAssign(values_, surfaceVoxels, inside);
    }
    const T &operator[](std::size_t i) const {
        const std::int32_t s = (*slot_)[i];
        return s < 0 ? inside_ : values_[std::size_t(s)];
    }
    T &surface(std::size_t i) { return values_[std::size_t((*slot_)[i])]; }  // i: a surface voxel
    const UnwrittenVector<T> &values() const { return values_; }              // surface voxels in unknown order

  private:
    std::shared_ptr<const std::vector<std::int32_t>> slot_;
    UnwrittenVector<T> values_;
    T inside_{};
};

// The unknowns of the diffusion solve: voxels optically thick enough for diffusion (sigma_t h >= 0.1) and
// not a surface's fringe, indexed 0..n-1 in OpenVDB leaf order, each linked to its six neighbours or to a
// boundary face.
struct SnowTopology {
    openvdb::Int32Tree::Ptr index;  // voxel -> unknown, -1 elsewhere
    // Sized unwritten (UnwrittenVector): buildSnowTopology's leaf loop writes every unknown's, in parallel.
    UnwrittenVector<openvdb::Coord> coord;
    UnwrittenVector<float> density;                     // kg/m^3
    VoxelLinks link;                                    // >= 0: neighbour unknown; < 0: face -1 - link
    UnwrittenVector<BoundaryFace> faces;                // the leaf loop's faces, copied in by a parallel loop
    std::shared_ptr<const std::vector<std::int32_t>> surfaceSlot;  // per unknown: index among surface voxels, or -1
    SurfaceValues<SurfacePatch> patches;  // per unknown (area 0 inside the snow)
    // Surface voxels: the surface voxels of their 3^3 block, themselves included (CSR over unknowns).
    std::vector<std::uint32_t> neighbourhoodStart, neighbourhood;
    // Voxels just under the surface, within a few mean free paths: the surface voxel nearest to them (-1
    // for the others) and how much of its radiance they carry (1 down to optical depth 3, 0 from 6, and 1 for
    // the first shellVoxels - 1 voxels under the surface whatever their depth: see buildSnowTopology).
    UnwrittenVector<std::int32_t> shellOwner;
    UnwrittenVector<float> shellWeight;

    std::size_t size() const { return coord.size(); }
    std::size_t surfaceVoxels() const { return patches.values().size(); }
    static bool isFace(std::int32_t link) { return link < 0; }
    static std::size_t faceIndex(std::int32_t link) { return std::size_t(-1 - link); }
    bool isAirFace(std::size_t voxel, int face) const {
        return isFace(link[voxel][face]) && !faces[faceIndex(link[voxel][face])].occluder;
    }
};

// How far (voxels) a link's occluder ray starts past the lower voxel's centre, up the axis: a surface through voxel
// centres then cuts the link below them.
constexpr double kLinkRayNudge = 1e-4;

// The occluder hit on the link from voxel `lower`'s centre to its neighbour's up axis `axis` (0..2), the ray starting
// kLinkRayNudge voxels up it (distance m from there): both voxels of a link test this one segment.
std::optional<RayCaster::Hit> occluderOnLink(const Medium &medium, const Occluders &occluders,
                                             const openvdb::Coord &lower, int axis);

// Whether an occluder lies between voxel c's centre and its neighbour's across face f (the topology's occluder face).
inline bool occluderAcross(const Medium &medium, const Occluders &occluders, const openvdb::Coord &c, int face) {
    return !occluders.empty() && occluderOnLink(medium, occluders, face & 1 ? c : c + faceStep(face), face / 2);
}

// Voxels with sigma_t h below this are too thin for diffusion: light crosses them (single scattering).
constexpr double kMinVoxelOpticalDepth = 0.1;
// A voxel thinner than this lying on a thicker one, under open air, is the fringe of a surface (a partly
// filled voxel of an antialiased surface): it belongs to the density ramp in front of the thick voxel,
// not to the unknowns, so the thick voxel carries the surface's radiance.
constexpr double kFringeOpticalDepth = 5.0;

// shellVoxels: how many voxels deep, at least, the surface's radiance is carried into the snow. Source grids
// `shellVoxels` times coarser than the density average a surface voxel with those under it (baked_grids.h):
// in thick snow they lie many optical depths deep, unseen, and carrying the surface's radiance keeps the
// average right.
SnowTopology buildSnowTopology(const Medium &medium, const Occluders &occluders, const SubProgress &progress,
                               int shellVoxels = 1);

// The offset of voxel k = 0..26 of a 3^3 block from its centre (13 is the centre), x fastest.
inline openvdb::Coord blockOffset(int k) { return openvdb::Coord(k % 3 - 1, k / 3 % 3 - 1, k / 9 - 1); }

// The curvature (per voxel, positive convex) of the surface around surface voxel j at cj: over the surface voxels k
// of its 3^3 block, weighted by the cosine w_k between their normals and j's, the ratio
// sum w_k n_k . t_k / sum w_k |t_k|^2, t_k their offsets from the block's weighted mean across n_j (so sum w_k t_k = 0:
// a sphere of R voxels with exact normals gives 1 / R), flat snow 0; worked out once per patch as the topology is
// built (SurfacePatch::curvature), read here by the topology's index. 0 where cj is no surface voxel (air, inner).
double surfaceCurvature(const SnowTopology &topo, const openvdb::Coord &cj,
                        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index);

}  // namespace firn
