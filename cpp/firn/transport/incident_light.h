#pragma once

#include <cstdint>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "firn/transport/block_masses.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/progress.h"
#include "firn/util/random.h"

namespace firn {

// Light reaching the snow from outside, per colour channel, before it scatters. Sun and sky light enter
// through the smooth surface patches of surface voxels (not through the voxels' staircase faces, which
// would shade each other).
struct IncidentLight {
    // One per beam (beamCount: the suns, then the lamps): irradiance (W/m^2 on a plane facing the light)
    // after the snow in front of the point (transmittance with the similarity-reduced extinction
    // sigma_tr = (1 - omega g) sigma_t: light that scattered forwards still travels with the beam) and
    // occluders (averaged over the sun's disc or the lamp).
    struct Beam {
        UnwrittenVector<glm::vec3> atVoxel;  // at each unknown's centre
        // Two things by the patch's side: facing the light, just outside the patch; facing away (cos > -0.5 to the
        // light, kRampBeamCosine in incident_light.cpp), the beam in the density ramp a voxel out along the normal
        // (rampInflow). 0 elsewhere. A reader must tell the two apart by the patch's facing to the light seen from
        // patchSurface (a lamp's way varies across a voxel): facesTowards(towardsBeam(b, patchSurface(i))).
        SurfaceValues<glm::vec3> atSurface;
    };
    std::vector<Beam> beams;
    // W/m^2 onto each surface voxel's patch from the sky, past occluders and snow, plus sun and sky light
    // that occluders reflect once towards the snow (0 inside the snow).
    SurfaceValues<glm::vec3> skyOnSurface;
    // Its first moment over the directions it arrives from (grey: the channels' mean; W/m^2 times a unit vector
    // towards the light): (2/3) n times the grey irradiance where it arrives evenly, leaning where it is lopsided
    // (a wall's sky from above only). Where a patch's returned sky leans (bake_surface_light.cpp, skyBeamPart).
    SurfaceValues<glm::vec3> skyAim;
    // Per surface voxel: which of its sky rays (SkyRays, bit k for ray k) snow hides; the snow's own light
    // arrives along them instead (gathered after a first solve, bake.cpp).
    SurfaceValues<std::uint64_t> snowRays;
    // Per surface voxel: which of the rays snow does not hide meet an occluder (bit k for ray k); occluders send the
    // snow's light back along them.
    SurfaceValues<std::uint64_t> occluderRays;
    // The share of the surface patches' sky rays that meet an occluder across the air, each weighted by the
    // occluder's grey albedo: occluders send the snow's light back along them (gathered after a first solve,
    // bake_snow_irradiance.cpp; worth passes of its own only where large, bake.cpp).
    double occluderShare = 0.0;
    // W/m^2 per boundary face, occluder faces only: sky light reaching the surface under thin snow.
    UnwrittenVector<glm::vec3> skyUnderSnow;
    // Per surface voxel: 1 where its sky was not traced but is its sky donors' mean (forEachSkyDonor: the traced
    // lattice patches about it, which agree within their noise); its snowRays and occluderRays are 0, and the light
    // gathered from other snow onto it is its donors' mean too (fillFromSkyDonors).
    SurfaceValues<std::uint8_t> fromDonors;
    std::size_t skyTraced = 0;  // surface voxels whose sky rays were traced
    bool skyLattice = false;    // traced on the lattice (skyRaysAt), where the sky is pooled over neighbours
};

// The rays a surface patch gathers its sky along: cosine-weighted around its normal, one jittered in each cell of a
// rows x columns grid over (1 - cos^2 of the angle from the normal, azimuth), the k-th depending only on (seed,
// stream, k), so a later pass can trace the same ones. Any count from 1 to kMaxRays (a patch's rays are one bit each
// of a 64-bit mask: IncidentLight::snowRays, occluderRays): rows the largest divisor of the count not above its square
// root (9 = 3 x 3, 6 = 2 x 3, 5 = 1 x 5), the longer side around the normal, where occluders differ most.
class SkyRays {
  public:
    static constexpr int kMaxRays = 64;
    explicit SkyRays(int samples);
    int count() const { return rows_ * columns_; }
    glm::dvec3 direction(const glm::dvec3 &normal, int k, std::uint64_t seed, std::uint64_t stream) const;

  private:
    int rows_, columns_;
};

// Light arriving along unit direction w (per channel) as its part of the grey first moment (IncidentLight::skyAim):
// the channels' mean times w.
inline glm::dvec3 greyMoment(const glm::dvec3 &light, const glm::dvec3 &w) {
    return (light.x + light.y + light.z) / 3.0 * w;
}

struct IncidentLightSettings {
    int skySamples = 16;  // rays per face, cosine-weighted, stratified
    int sunSamples = 4;   // points on each sun's disc or lamp per shadow test
    std::uint64_t seed = 0;
    bool skyOverNeighbours = false;  // skyOnSurface averaged over like-facing neighbours (averageOverNeighbours)
};

IncidentLight computeIncidentLight(const Scene &scene, const SnowTopology &topology,
                                   const IncidentLightSettings &settings, const SubProgress &progress);

// Surface values (W/m^2 onto each patch) averaged over the smooth surface voxels of each smooth surface voxel's
// 3^3 block whose normals lie within about 25 degrees of its own: neighbours see nearly the same sky, so a few
// rays each (SkyRays, each voxel's own jitter) pool into a less noisy estimate. Sharp edges keep their own.
void averageOverNeighbours(const SnowTopology &topology, SurfaceValues<glm::vec3> &values);
// Neighbours whose normals are within this cosine (about 25 degrees) of a voxel's share its sky (averageOverNeighbours,
// forEachSkyDonor).
constexpr double kLikeFacingCosine = 0.9;

// The sky varies slowly over most of a surface (an open roof, flat ground, a cavity's floor): it is traced on a
// coarse lattice of surface voxels, those whose two coordinates across their normal's largest axis are even (a quarter
// of a flat surface), and at sharp voxels. Another surface voxel's sky donors are the lattice voxels of its 3^3 block,
// smooth and facing within about 25 degrees of it; where at least two agree within their noise (skyDonorsAgree) it
// takes their mean, elsewhere (shadow edges, the ground at a wheel, too few donors) its own rays are traced.
bool onSkyLattice(const SnowTopology &topology, std::size_t i);
// The rays surface voxel i traces for `samples` asked: with the lattice (`lattice`), kLatticeRays times as many on it
// and at sharp voxels, whose sky the voxels between take: FINAL pools each voxel's sky over its like-facing neighbours
// (averageOverNeighbours), and at the samples asked the lattice's means left ~4 of its ~9 independent estimates (the
// car's grid noise 1.52x, as 4 rays everywhere; docs/benchmarks.md, car-sky-sparse). Without it (REFERENCE: no
// pooling) every surface voxel traces `samples`.
constexpr int kLatticeRays = 2;
SkyRays skyRaysAt(const SnowTopology &topology, std::size_t i, int samples, bool lattice);
template <typename Visit>
void forEachSkyDonor(const SnowTopology &topo, std::size_t i, const Visit &visit) {
    for (std::size_t k = topo.neighbourhoodStart[i]; k < topo.neighbourhoodStart[i + 1]; ++k) {
        const std::uint32_t j = topo.neighbourhood[k];
        const SurfacePatch &donor = topo.patches[j];
        if (j != i && !donor.sharp && onSkyLattice(topo, j) &&
            glm::dot(topo.patches[i].normal, donor.normal) >= kLikeFacingCosine)
            visit(std::size_t(j));
    }
}
// Each surface voxel marked in `fromDonors` given its sky donors' mean of `values`. `leaning`: the values are a first
// moment over the directions light arrives from (IncidentLight::skyAim), each donor's turned with its normal onto the
// voxel's first: untouched, a donor 25 degrees round a curve would make an even sky lean by a third (skyBeamPart).
void fillFromSkyDonors(const SnowTopology &topology, const SurfaceValues<std::uint8_t> &fromDonors,
                       SurfaceValues<glm::vec3> &values, bool leaning);

// Surface voxel i's patch itself, on the snow's surface (patchOutside: past its ramp): half a voxel out from its
// centre along its normal (m, world), where a light's beam enters it; its way to a lamp and its occluders' shadow are
// taken there. Taken from the voxel centre, half a voxel under the surface, a lamp 10 voxels from a ball stood higher
// over every patch and the patches past its terminator took its light (docs/benchmarks.md, lamp-near).
glm::dvec3 patchSurface(const Medium &medium, const SnowTopology &topology, std::size_t i);

// Where light meets surface voxel i's patch: out along its normal, past the density ramp and any fringe, or where the
// density is least between the patch's ramp and other snow's (a narrow groove's opposite wall). `density`:
// the caller's (one per thread; an accessor made per call started each lookup from the tree's root).
glm::dvec3 patchOutside(const Medium &medium, const SnowTopology &topology, std::size_t i, Medium::Accessor &density);

// Where a ray from surface voxel i's patch along w (unit, leaving the patch) lies as high above the patch as
// patchOutside (past the density ramp and any fringe; the ray at most 20 times that height long): a light's shadow
// taken from there falls where the snow in front casts it. From patchOutside itself, up to 3.5 voxels out along
// the normal, a small piece's patches looked past the shadow of a piece its own size. A sharp voxel's ray leaves its
// air face most open to w (SurfacePatch::airFaceMostOpenTo), as high above that face as the face's own
// ramp reaches.
glm::dvec3 patchOutsideAlong(const Medium &medium, const SnowTopology &topo, std::size_t i, const glm::dvec3 &w,
                             Medium::Accessor &density);

// Reduced extinction per unit density, per channel: k (1 - omega g) (m^2/kg).
glm::dvec3 reducedExtinctionPerDensity(const VolumeOptics &optics);

// How light crossing snow is attenuated: inside the snow, as the similarity beam (forward-scattered light
// travels on, sigma_tr); on its way to a surface from outside, uncollided (sigma_t: what other snow
// scatters towards the surface arrives as that snow's own radiance, gathered separately); a beam on its way
// to a surface patch, uncollided plus the share of each crossed piece's forward-scattered light that still
// reaches the patch (forwardShare: all of it right behind the piece, a fraction further off); through a density
// ramp to the light it scatters once there, the delta-scaled beam (Forward: the share g^2 of what scatters keeps the
// beam's way, sigma_t (1 - omega g^2), as forwardPeakThrough's).
enum class Crossing { Beam, Uncollided, Spreading, Forward };

// Of the light a piece of snow of radius r (m, across the beam) and optical depth tau (along it) scatters
// forwards, the share reaching a point d (m) behind it on its axis: 1 - 1 / sqrt(1 + (r / (d theta))^2). Near
// the axis Henyey-Greenstein's phase function is the 2-D Cauchy (Poisson) kernel of width theta_1 = (1 - g) /
// sqrt(g), whose widths add over n scatterings (theta = n theta_1, n = tau / (1 - e^-tau) the mean count of
// those that scattered); the share is that kernel's mass within the disc's half-angle r / d.
double forwardShare(double radius, double distance, double opticalDepth, double g);
double forwardConeWidth(double opticalDepth, double g);  // theta (rad) above

// The lights that reach into the snow as beams, each from one direction at a point: the scene's suns
// (beam b < suns.size()), then its lamps (towards their centre).
std::size_t beamCount(const Scene &scene);
glm::dvec3 towardsBeam(const Scene &scene, std::size_t b, const glm::dvec3 &point);  // unit

// The way to beam b's light from a voxel face's centre (`face`, m, world), the voxel's centre `centre`: a near lamp's
// beam spreads, and what it loses sideways leaves through the side faces rather than counting as scattered. A point
// lamp's light spreads radially (its way from the face itself); an area lamp's piece of half-width a at distance d
// spreads less: on its axis its light vector's divergence per unit irradiance is 2 d / (d^2 + a^2), not 2 / d, so the
// way's change from the centre's is scaled by d^2 / (d^2 + a^2) (a^2 = area / pi; review s51: the way from the face
// alone took ball_issue's bias under the 40 cm lamp from -4.7 to -8.3 %).
glm::dvec3 faceWayToBeam(const Scene &scene, std::size_t b, const glm::dvec3 &centre, const glm::dvec3 &face);
// The cosine between face f's outward normal and that way at its centre, for the voxel of width h (m) centred at
// `centre`: positive where beam b enters through the face. A sun's way is the same everywhere: its cosine is one
// component of its direction (inline, since the assembly asks it six times a voxel).
double nearFaceCosineToBeam(const Scene &scene, std::size_t b, const glm::dvec3 &centre, int f, double h);
inline double faceCosineToBeam(const Scene &scene, std::size_t b, const glm::dvec3 &centre, int f, double h) {
    if (b < scene.suns.size()) return (f & 1) ? scene.suns[b].direction[f / 2] : -scene.suns[b].direction[f / 2];
    return nearFaceCosineToBeam(scene, b, centre, f, h);
}

struct BeamSample {
    glm::vec3 irradiance{0.0f};  // W/m^2 on a plane facing the light
    bool snowBlocks = false;     // the snow in front leaves less than 1e-5 of it
};

// Beam b at a point: snow transmittance from `point` towards the light times the light's irradiance
// seen past occluders from `shadowPoint` (default: the same point), over `samples` points of a sun's disc
// or a lamp. Crossing::Spreading reads the snow's `blocks` (its mass per coarse block).
BeamSample beamAt(const Scene &scene, std::size_t b, const glm::dvec3 &point, int samples, std::uint64_t seed,
                  std::uint64_t stream, Medium::ColumnMarcher &marcher, const glm::dvec3 *shadowPoint = nullptr,
                  Crossing crossing = Crossing::Beam, const BlockMasses *blocks = nullptr);

// Radiance (W/m^2/sr) an occluder sends from point q (unit normal n facing the viewer) after one reflection of
// sun and sky light, each estimated with one ray.
glm::dvec3 reflectedByOccluder(const Scene &scene, const glm::dvec3 &q, const glm::dvec3 &n, const Rgb &albedo,
                               Rng &rng, Medium::ColumnMarcher &marcher);

}  // namespace firn
