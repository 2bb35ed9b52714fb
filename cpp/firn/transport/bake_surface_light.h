#pragma once

// The light leaving the snow's surface voxels, from the three channels' solves.

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "firn/transport/bake_diffusion_system.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/transport/source_lobe.h"
#include "firn/util/progress.h"

namespace firn::bake {

// What the solves yield for surface voxels, per channel: the light leaving through their patch, as power
// times angular shape (W; radiance after dividing by pi A).
struct SurfaceLight {
    // What returns of the light that entered there, over and above the escape function's share of it
    // (sharp: it follows shadows; on a sharp edge, SurfacePatch::sharp, the voxel's exit lobe instead, its
    // faces' light fitted already) ...
    BroadLobe returned;
    // ... the beams' light that crosses the snow and leaves through the patch on its far side: a lobe of
    // k = g (l0 in W per channel) about the mean of the beams' directions (per voxel; length <= 1) ...
    glm::vec3 crossing{0.0f}, crossingAxis{0.0f};
    // ... the suns' light returned sharply forwards (smooth patches and sharp edges' faces; SunPeak), the peaked
    // lobe's p0 per channel and grey first moment p1 (radiance, source_lobe.h) ...
    glm::vec3 peak0{0.0f}, peak1{0.0f};
    // ... of which the beams the density ramp a voxel out along the normal scatters itself (beamLightsRamp there:
    // beamsInRamp sets their ramp light against this part alone) ...
    glm::vec3 rampPeak0{0.0f}, rampPeak1{0.0f};
    // ... and all light leaving (W per channel), which leaves in the escape function's shape (smooth,
    // but spread unevenly over a voxel staircase; the suns' light that escaped at once left out: it leaves
    // downstream, SunReturned).
    glm::vec3 leaving{0.0f};
    // Of `leaving`'s green, the part the sky and other snow drive (W, the rest the beams'), where the solves kept the
    // beams apart (SurfaceTerms::skyLeaving; else 0).
    float skyLeaving = 0.0f;
};

// The air faces of sharp edge voxels (SurfacePatch::sharp) that go on as a flat wall away from the voxel's other air
// faces, each with its own exit lobe (exitLobe of the face's form, the voxel's crossing beams added): the air across
// such a face carries that lobe (facingAverage), where the voxel's one lobe shows a lit face and a dark one alike
// (box_sharp's shadowed side under its lit top read 1.4 times the Monte Carlo head-on; docs/benchmarks.md, edge-faces).
// Not where the face stops at a step (a ball's staircase: its face's own form is not the curved surface's exit).
struct EdgeFaceLobes {
    struct Voxel {
        std::uint32_t key = 0;  // the unknown
        std::uint8_t flat = 0;  // bit f: air face f holds its own lobe
        std::array<BroadLobe, 6> lobe{};
        // What leaves through air face f of the suns returned sharply forwards (SunPeak), as a multiple of the
        // voxel's stored peaked lobe: a lit top's grazing return leaves through the top, not the shadowed side beside
        // it. The stored lobe is what the voxel's one value shows of its faces' peaks (peakSeenThroughFaces) where
        // its faces are walls, else the peaks' sum.
        std::array<float, 6> peakShare{};

        // Whether every air face of the voxel's patch goes on as a flat wall (holds its own lobe): a corner of flat
        // walls, each face its own surface, which shows its own peak to the air across it and to cameras through
        // its projected area (peakSeenThroughFaces). Where a face stops at a step the faces stand for one curved
        // surface (a ball's staircase), whose peak leaves through it whole (seen through the faces, ball_issue's view
        // against the sun lost 2 % of its light; docs/benchmarks.md, corner-lean).
        bool facesAreWalls(const SurfacePatch &patch) const {
            for (int f = 0; f < 6; ++f)
                if (patch.share[f] > 0.0f && !(flat >> f & 1u)) return false;
            return true;
        }
    };
    std::vector<Voxel> voxels;  // in key order

    // Voxel `key`'s faces, or nullptr where it holds none.
    const Voxel *find(std::size_t key) const {
        const auto it = std::lower_bound(voxels.begin(), voxels.end(), key,
                                         [](const Voxel &v, std::size_t k) { return v.key < k; });
        return it != voxels.end() && it->key == key ? &*it : nullptr;
    }
};

// The light gathered from other snow onto the surface patches and its moment (SnowIrradiance, read in place); none
// before the first gathering.
struct SnowLight {
    const SurfaceValues<glm::vec3> *light = nullptr, *aim = nullptr;
};

// The light leaving voxel i's neighbourhood towards n (leavingOf(j), W) and its area (m^2): the surface voxels
// of its 3^3 block weighted by the cosine between n and their normals, voxels on a sharp edge other than i left
// out (surfaceRadiance says why); with a finite `reach` (voxels) also by a Gaussian of that width in their distance
// from i, so light that varies within a voxel is spread less.
template <typename T, typename LeavingOf>
std::pair<T, double> neighbourhoodOutflow(const SnowTopology &topo, std::size_t i, const glm::dvec3 &n,
                                          const LeavingOf &leavingOf,
                                          double reach = std::numeric_limits<double>::infinity()) {
    assert(reach > 0.0);
    const bool near = std::isfinite(reach);
    // The Gaussian by a neighbour's squared distance from i (0 to 3 voxels^2: the block is i's +-1 voxels).
    std::array<double, 4> falloff{1.0, 1.0, 1.0, 1.0};
    if (near)
        for (int squared = 1; squared < 4; ++squared) falloff[squared] = std::exp(-squared / (2.0 * reach * reach));
    T leaving(0.0);
    double area = 0.0;
    for (std::size_t k = topo.neighbourhoodStart[i]; k < topo.neighbourhoodStart[i + 1]; ++k) {
        const std::uint32_t j = topo.neighbourhood[k];
        const SurfacePatch &other = topo.patches[j];
        if (other.sharp && j != i) continue;
        int squared = 0;
        if (near) {
            const openvdb::Coord d = topo.coord[j] - topo.coord[i];
            squared = d.x() * d.x() + d.y() * d.y() + d.z() * d.z();
            assert(squared < 4);
        }
        const double w = std::max(0.0, glm::dot(n, other.normal)) * falloff[squared];
        leaving += w * leavingOf(j);
        area += w * other.area;
    }
    return {leaving, area};
}

// The density of the snow beneath surface voxel i's patch of normal n.
double densityBeneath(const SnowTopology &topo, std::size_t i, const glm::dvec3 &n);

// The unit direction along a surface of normal n in which light travelling along d moves.
glm::dvec3 travelAlong(const glm::dvec3 &d, const glm::dvec3 &n);

// Surfaces that take a sun at most this grazingly (mu0 = cos of its angle to the normal) leave the sun in their
// density ramp to the ramp itself (beamsInRamp; 0.2 before branch rim-forward: half of a ball's rim light seen against
// the sun entered where mu0 >= 0.3, and 0.4 took ball_issue's view there -14 -> -13 %, docs/benchmarks.md).
constexpr double kGrazingSunCosine = 0.4;

// Whether beam b (a sun, lamp or area lamp's piece) meeting the carrying surfaces at mu0 (the cosine of its way at c to
// their normal) scatters its light in the ramp (beamsInRamp). Suns and area lamps' pieces: grazing or past the
// terminator (mu0 < kGrazingSunCosine). Point and spot lamps only on the lit side (0 <= mu0): their ramp past the
// terminator, where the lamp's ways fan out over the limb, doubled the view against the lamp (ball_grey +18 -> +82 %,
// ball_issue +13 -> +101 %), while an area lamp's pieces' ways do not line up on one camera (docs/benchmarks.md,
// lamp-shell, lamp-ramp).
bool beamLightsRamp(const Scene &scene, std::size_t b, double mu0);

// Lobe `lobe` of surface voxel i's channel c with the crossing beams' light (SurfaceLight::crossing) added by its
// moments: light scattered forwards many times is broader than one scattering's peak (in the peaked lobe, k = g:
// ball_forward 17.6 % against 17.1 %, seen against the sun -29 % against -21 %; spray_lumps 20.1 % against 19.7 %;
// docs/bake.md).
inline SourceLobe withCrossing(const SourceLobe &lobe, const SurfaceLight &light, double area, int c, double g) {
    const double crossing = light.crossing[c] / area;  // its lobe's l0 (radiance)
    return {lobe.l0 + crossing, lobe.l1 + 3.0 * crossingAnisotropy(g) * crossing * glm::dvec3(light.crossingAxis)};
}

// The three channels' light leaving each surface voxel (`out`), from their systems' surface terms and fluences phi,
// and where `flatFaces` the sharp edge voxels' flat faces' own lobes (`edgeFaces`; else none). Stops with
// firn::Cancelled when `progress` is cancelled.
void surfaceLight(const Scene &scene, const SnowTopology &topo, const IncidentLight &light, const SnowLight &snow,
                  const std::array<SurfaceTerms, 3> &terms, const std::array<UnwrittenVector<double>, 3> &phi,
                  bool flatFaces, SurfaceValues<SurfaceLight> &out, EdgeFaceLobes &edgeFaces,
                  const SubProgress &progress);

}  // namespace firn::bake
