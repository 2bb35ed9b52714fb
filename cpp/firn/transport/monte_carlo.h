#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/transport/scene.h"
#include "firn/util/color.h"
#include "firn/util/progress.h"
#include "firn/util/random.h"

namespace firn {

struct Ray {
    glm::dvec3 origin;     // m, world space
    glm::dvec3 direction;  // unit
};

// The direction the brightest sun's beam travels (0 without suns).
glm::dvec3 brightestBeam(const Scene &scene);

// The directions the traced source is also gathered in (bake_traced_voxels.cpp fits its lobes to them), unit: the
// cube's 6 faces, 12 edges and 8 corners, and about the beam's travel (brightestBeam; +z without one) the axis and
// rings of 6 at 10 and 25 degrees, where the peaked lobe falls by 3 and 20 times at g 0.87.
constexpr int kSourceDirections = 39;
using SourceDirections = std::array<glm::dvec3, kSourceDirections>;
SourceDirections sourceDirections(const glm::dvec3 &beamTravel);

// The moments of the source function a voxel's snow scatters, per channel: mean l0 and first moment 4 pi l1 / 3
// (w: the direction the light leaves; l1 column c is channel c's vector), W/m^2/sr: the baked grids' form.
struct SourceEstimate {
    Rgb l0{0.0};
    glm::dmat3 l1{0.0};
    Rgb beamL0{0.0};         // of which the suns' and lamps' direct beams scattered once
    glm::dmat3 beamL1{0.0};  // (the baked grids' peaked lobe)
    // The directions t the arriving light travels (beams included), weighted by what the snow scatters of it
    // as l0 is and averaged over the channels: their second and third moments, mean(l0) E[t t^T] and
    // mean(l0) E[t_i t t^T] (third[i]); the first is mean(l1) / (3 g). Light scattered by Henyey-Greenstein
    // keeps g^n of the arriving light's n-th Legendre moment about any axis: how peaked the source is.
    glm::dmat3 second{0.0};
    std::array<glm::dmat3, 3> third{};
    // The source itself seen from each of sourceDirections(brightestBeam) (grey: the channels' mean), W/m^2/sr: the
    // arriving light through the exact Henyey-Greenstein phase function, not its moments.
    std::array<double, kSourceDirections> toward{};
    long steps = 0;  // tracking steps (density lookups) of all its paths and shadow rays: what the estimate cost
};

SourceEstimate &operator+=(SourceEstimate &a, const SourceEstimate &b);

// The source cameras see where they collide in front of a face of a voxel, read as the render reads it: each
// collision's light weighted by the trilinear hat of the air neighbour across the face (`carried`: what that
// neighbour holds) and by the voxel's (`shown`: what the voxel's own value shows those cameras); carried and
// shown read there give the light they saw, on average (MonteCarloReference::faceSourceIn).
struct FaceEstimate {
    SourceEstimate carried, shown;
    double shownShare = 0.0;  // the voxel's mean hat share over the collisions
};

// Light arriving at the points of a voxel, summed: fluence (W/m^2) and flux (column c: channel c's vector, W/m^2
// along the direction light travels), scattered light and the lights' direct beams apart, and the second and
// third moments of the directions t light travels, weighted by what the snow scatters of it (albedo, grey).
struct ArrivingLight {
    Rgb phi{0.0}, phiBeam{0.0};
    glm::dmat3 flux{0.0}, fluxBeam{0.0};
    glm::dmat3 second{0.0};            // sum of mean(albedo phi) t t^T
    std::array<glm::dmat3, 3> third{};  // sum of mean(albedo phi) t_i t t^T

    // Light of `fluence` travelling along `travel`: a direct beam's, or scattered light's.
    void add(const Rgb &fluence, const glm::dvec3 &travel, bool beam, const VolumeOptics &optics);
    void addScaled(const ArrivingLight &other, double weight);
    ArrivingLight &operator+=(const ArrivingLight &other);
};

// The source the light arriving at a voxel's points scatters towards each of `directions`, summed: what the fit
// by direction reads (traced_source.h), gathered apart from ArrivingLight so that light tracing keeps it only
// for the voxels so fitted (312 of 792 bytes per voxel).
struct ArrivingToward {
    std::array<double, kSourceDirections> toward{};  // sum of mean(albedo phi) HG(t . w_j) (SourceDirections)

    void add(const Rgb &fluence, const glm::dvec3 &travel, const VolumeOptics &optics, const SourceDirections &directions);
    void addScaled(const ArrivingToward &other, double weight);
    ArrivingToward &operator+=(const ArrivingToward &other);
};

// The source a voxel's snow scatters of the light arriving in it, `sum` and `toward` (none: its toward left 0)
// gathered with weights adding up to `weights` (extinction: the extinction-weighted mean the renderer's emission
// needs).
SourceEstimate sourceOf(const ArrivingLight &sum, const ArrivingToward *toward, double weights,
                        const VolumeOptics &optics);

// Light travelling forwards from the lights (light tracing): power (W, per channel) leaving a point along a ray.
struct Photon {
    Ray ray;
    Rgb power{0.0};
    bool straightFromLight = false;  // a sun's beam: its first collision is the single scattering sourceIn's beams hold
};

// A photon's real collision in the medium at p (m), with the power arriving there (W) and the direction it travels.
using CollisionTally = std::function<void(const glm::dvec3 &p, const glm::dvec3 &travel, const Rgb &power)>;

struct RadianceEstimate {
    Rgb mean{0.0};           // W/m^2/sr
    Rgb standardError{0.0};  // of the mean
};

// What MonteCarloReference::sourceIn gathers, and where its points lie.
enum class Gathering {
    Spread,     // all orders, the points spread over the voxel, weighted by extinction
    WhereSeen,  // all orders, the points drawn where cameras see the voxel's stored source, of equal weight
                // (VisiblePoints: in a voxel of many optical depths, its first optical depth from each side, and
                // the trilinear hat's reach)
    BeamsOnly,  // the direct beams only, spread (beamL0, beamL1 and their share of the moments): what light
                // tracing leaves to each voxel (light_tracing.h)
};

// Brute-force volumetric path tracing of the scene: the reference the bake is tested against and the
// REFERENCE quality. It shares no approximation with the bake: delta tracking through the trilinear
// density with a global majorant, Henyey-Greenstein sampling at every real collision (all orders, no
// truncation), ratio-tracked shadow rays to the suns and lamps, Lambertian occluders, the sky where paths
// escape.
//
// Estimates, for each camera ray, the radiance the snow scatters towards the camera: paths whose first
// event is a scattering in the medium. It excludes what a renderer draws itself behind the snow (sky and
// surfaces seen through it, attenuated by exp(-tau)); that is exactly what the baked emission stands for.
class MonteCarloReference {
  public:
    explicit MonteCarloReference(Scene scene);

    RadianceEstimate estimate(const Ray &ray, int samples, std::uint64_t seed, std::uint64_t stream) const;

    // Many rays in parallel; deterministic for a given seed. Reports to and honours `progress`.
    std::vector<RadianceEstimate> estimate(const std::vector<Ray> &rays, int samplesPerRay, std::uint64_t seed,
                                           Progress *progress = nullptr) const;

    // The source function in one voxel, from `samples` points spread over it (a randomly shifted Kronecker
    // sequence over position and direction, stratified and seeded; weighted by extinction, as
    // the renderer's emission is), each gathering the light arriving from one uniformly drawn direction,
    // all orders, and every light's direct beam: omega / (4 pi) (phi + 3 g F . w),
    // the Henyey-Greenstein phase function to first order in w, with the exact fluence phi and flux F; the
    // direct beams' share apart; the higher moments of the directions the light travels, which tell how peaked
    // the source is; and the exact source in directions().
    // `how`: see Gathering. Cancelled through `progress` within its paths (WorkCheck on their tracking steps): one
    // voxel's paths run for seconds in dense snow.
    SourceEstimate sourceIn(const openvdb::Coord &voxel, int samples, std::uint64_t seed, std::uint64_t stream,
                            Gathering how = Gathering::Spread,
                            const SubProgress &progress = SubProgress(nullptr, 0.0, 1.0)) const;

    // What cameras looking at the air face `face` (0..5: -x, +x, -y, +y, -z, +z) of a thick voxel see of it, from
    // `samples` points where they collide (facePoints), all orders: split by the trilinear hat between the air
    // neighbour's value and the voxel's (FaceEstimate). Its steps in `carried`. Cancelled as sourceIn.
    FaceEstimate faceSourceIn(const openvdb::Coord &voxel, int face, int samples, std::uint64_t seed,
                              std::uint64_t stream, const SubProgress &progress = SubProgress(nullptr, 0.0, 1.0)) const;

    const Scene &scene() const { return scene_; }
    // Where every estimate of this reference gathers the exact source (sourceIn, light tracing's tallies), and
    // so where a fit reads it: sourceDirections(brightestBeam(scene())).
    const SourceDirections &directions() const { return directions_; }

  private:
    Scene scene_;
    SourceDirections directions_;
};

// A render in which the renderer scatters in the optically thin snow and draws the baked emission elsewhere
// (benchmarks.md, thin-ring): per thread, the baked emission seen along a camera ray up to tMax (m), already
// weighted by 1 - scatterShare; the baked source at a point towards w (W/m^2/sr, per unit extinction, weighted
// likewise); and the share of the snow at a point that scatters (1 in thin snow, 0 in baked snow, trilinear between).
struct MixedRender {
    std::function<Rgb(const Ray &camera, double tMax)> emittedAlong;
    std::function<Rgb(const glm::dvec3 &p, const glm::dvec3 &w)> emittedAt;
    std::function<double(const glm::dvec3 &p)> scatterShare;
    int bounces = 1 << 30;  // the renderer's volume bounces: scatterings a path continues after (each lit by the lights)
};

// MonteCarloReference::estimate's rays rendered so: the camera segment's emission integrated, the paths' own
// collisions scattering their share (the lights' single scattering at each, as the reference) and collecting
// the emission of the rest (a collision estimate: the mean of sigma_t S exp(-tau) over collisions is S's).
std::vector<RadianceEstimate> estimateMixed(const MonteCarloReference &reference, const std::vector<Ray> &rays,
                                            int samplesPerRay, std::uint64_t seed,
                                            const std::function<MixedRender()> &perThread);

class PathTracer;

// Light tracing (light_tracing.h) with the reference's tracking, on one thread: its density accessors are built
// once for many photons. Its tracking (density lookups) jumps over blocks without snow.
class PhotonTracer {
  public:
    explicit PhotonTracer(const MonteCarloReference &reference);
    ~PhotonTracer();

    // The paths above run forwards: follows `photon` through the medium (delta tracking, Henyey-Greenstein at
    // every real collision) and off the occluders (Lambertian) until it leaves the box [boxMin, boxMax] (within
    // the medium's bounds) or roulette ends it, calling `tally` at every real collision (but a sun beam's first).
    void follow(const Photon &photon, const glm::dvec3 &boxMin, const glm::dvec3 &boxMax, Rng &rng,
                const CollisionTally &tally);

    // All the light arriving at `ray.origin` travelling along -ray.direction (sky, occluders' reflections, the
    // medium's scattering; not the suns' and lamps' direct beams), one sample, W/m^2/sr.
    Rgb radianceArriving(const Ray &ray, Rng &rng);

    long steps() const;  // tracking steps so far

    // Whether p lies inside a closed occluder, where no light reaches (the gathering's test, sourceIn's).
    bool enclosed(const glm::dvec3 &p) const;

  private:
    std::unique_ptr<PathTracer> tracer_;
};

}  // namespace firn
