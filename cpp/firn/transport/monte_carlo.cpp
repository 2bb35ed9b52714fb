#include "firn/transport/monte_carlo.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/snow_topology.h"
#include "firn/transport/visible_points.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"
#include "firn/util/work_check.h"

namespace firn {

namespace {

// The tracking steps a tracer took since `counted` (its steps when last asked), which becomes `now` (WorkCheck units).
std::uint64_t stepsSince(long now, long &counted) {
    const long since = now - counted;
    counted = now;
    return std::uint64_t(since);
}

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kSurfaceEpsilon = 1e-5;  // m: rays leaving a surface start this far off it
constexpr long kMaxEvents = 10'000'000;   // a safety net only; paths end by escaping or roulette

double maxComponent(const Rgb &c) { return std::max({c.x, c.y, c.z}); }

// Distance (m) along d from p, inside the box [lo, hi], to where the ray leaves it.
double boxExit(const glm::dvec3 &lo, const glm::dvec3 &hi, const glm::dvec3 &p, const glm::dvec3 &d) {
    double t = kInfinity;
    for (int a = 0; a < 3; ++a) {
        if (d[a] > 0.0) t = std::min(t, (hi[a] - p[a]) / d[a]);
        else if (d[a] < 0.0) t = std::min(t, (lo[a] - p[a]) / d[a]);
    }
    return t;
}

// Points of [0, 1)^5 (a voxel's position and a direction) from the R5 Kronecker sequence, n alpha mod 1 with
// alpha_i = phi^-i, phi the root of x^6 = x + 1 (Roberts 2018), shifted at random (Cranley-Patterson): every
// projection stratified, seeded. Against independent draws (bench/bake_suite.py --seeds, mean error per block and
// the render's spread across seeds): ball_thin 4.8 -> 4.6 % (3.5 -> 2.8 %), spray_lumps 14.1 -> 13.0 % (16
// seeds), spray_dense 25.0 -> 21.8 % (4 seeds), at the same cost; most of what is left is the paths' own noise.
class KroneckerSequence {
  public:
    explicit KroneckerSequence(Rng &rng) {
        constexpr double phi = 1.1347241384015194;
        for (int i = 0; i < 5; ++i) alpha_[i] = std::pow(phi, -(i + 1)), x_[i] = rng.uniform();
    }
    std::array<double, 5> next() {
        for (int i = 0; i < 5; ++i) x_[i] += alpha_[i], x_[i] -= std::floor(x_[i]);
        return x_;
    }

  private:
    std::array<double, 5> alpha_{}, x_{};
};

// Points of [0, 1)^3 from the sequence's first three coordinates (the draws of VisiblePoints and facePoints).
std::function<std::array<double, 3>()> threeOf(KroneckerSequence &sequence) {
    return [&sequence] {
        const std::array<double, 5> u = sequence.next();
        return std::array<double, 3>{u[0], u[1], u[2]};
    };
}

}  // namespace

// One path tracer per thread: holds a density accessor.
class PathTracer {
  public:
    // With `skipEmpty`, tracking jumps over blocks without snow (sampleCollision): the same estimates, other draws.
    explicit PathTracer(const MonteCarloReference &reference, bool skipEmpty = false)
        : skipEmpty_(skipEmpty),
          scene_(reference.scene()),
          medium_(*scene_.medium),
          density_(medium_),
          support_(medium_.supportAccessor()),
          k_(medium_.optics().extinctionPerDensity),
          sigmaBar_(std::max(medium_.maxSigmaT(), 1e-12)),
          directions_(reference.directions()) {}

    // Radiance scattered by the medium towards the camera along one camera ray, one sample. With
    // `unscattered`, also the sky and surfaces seen straight along the ray: all the light arriving at its origin.
    Rgb sample(const Ray &camera, Rng &rng, bool unscattered = false) {
        return walk<false>(camera, rng, unscattered, nullptr);
    }

    // The same path rendered as `mixed` renders it, less the camera segment's emission (the caller's, once per ray).
    Rgb sample(const Ray &camera, Rng &rng, MixedRender &mixed) { return walk<true>(camera, rng, false, &mixed); }

    // All light arriving at p, one sample: radiance from one direction drawn uniformly over the sphere (all
    // orders, scattered light only) and each light's direct beam, added with weight w. (u1, u2) draw the
    // direction.
    // Without `scattered`, the direct beams only.
    void sampleArriving(const glm::dvec3 &p, double w, double u1, double u2, Rng &rng, ArrivingLight &sum,
                        ArrivingToward &toward, bool scattered) {
        const VolumeOptics &optics = medium_.optics();
        if (scattered) {
            const glm::dvec3 d = sampleUniformCone(glm::dvec3(0.0, 0.0, 1.0), -1.0, u1, u2);
            const Rgb L = 4.0 * kPi * sample(Ray{p, d}, rng, true);
            sum.add(w * L, -d, false, optics), toward.add(w * L, -d, optics, directions_);
        }
        for (std::size_t b = 0; b < lightCount(); ++b) {
            glm::dvec3 towards;
            const Rgb E = lightIrradiance(b, p, 0.0, towards, rng);
            if (E != Rgb(0.0)) sum.add(w * E, -towards, true, optics), toward.add(w * E, -towards, optics, directions_);
        }
    }

    // Light tracing: the photon forwards until it leaves the box [lo, hi] (what lies beyond reaches it again only
    // as the light arriving there, which the caller's photons carry) or roulette ends it.
    void follow(const Photon &photon, const glm::dvec3 &lo, const glm::dvec3 &hi, Rng &rng, const CollisionTally &tally) {
        glm::dvec3 p = photon.ray.origin, d = photon.ray.direction;
        Rgb throughput(1.0);
        bool straight = photon.straightFromLight;
        for (long event = 0; event < kMaxEvents; ++event) {
            const double tExit = boxExit(lo, hi, p, d);
            if (!(tExit > 0.0)) return;
            const double tCollision = sampleCollision(p, d, tExit, rng);
            const float tNear = event == 0 ? 0.0f : float(kSurfaceEpsilon);
            const std::optional<RayCaster::Hit> hit = scene_.occluders->caster().intersect(
                glm::vec3(p), glm::vec3(d), tNear, float(std::min(tCollision, tExit)));
            if (hit) {
                p += double(hit->distance) * d;
                const glm::dvec3 n = glm::dot(glm::dvec3(hit->normal), d) < 0.0 ? glm::dvec3(hit->normal)
                                                                                  : -glm::dvec3(hit->normal);
                throughput *= scene_.occluders->albedo(hit->triangle);
                d = sampleCosineHemisphere(n, rng.uniform(), rng.uniform());
            } else if (tCollision < kInfinity) {
                p += tCollision * d;
                if (!straight) tally(p, d, photon.power * throughput);
                throughput *= medium_.optics().albedo;
                d = sampleHenyeyGreenstein(d, medium_.optics().g, rng.uniform(), rng.uniform());
            } else {
                return;
            }
            straight = false;
            const double q = maxComponent(throughput);
            if (q < 0.25) {
                if (rng.uniform() >= q) return;
                throughput /= q;
            }
        }
    }

    double sigmaT(const glm::dvec3 &p) { return k_ * density_.at(medium_.worldToIndex(p)); }

    // Whether p lies inside a closed occluder (the snow's surface mesh under thrown lumps, a body): no light
    // reaches there, and a path started there bounces off the inside until roulette (some 700 times at the
    // snow's albedo 0.998). Inside, the rays straight up and straight down both leave through a back face of a
    // closed surface (wound counter-clockwise seen from outside). Open sheets are not asked, whatever their
    // winding: snow between a ground wound downwards and a roof above is outside both.
    bool enclosed(const glm::dvec3 &p) const {
        const Occluders &occluders = *scene_.occluders;
        const glm::vec3 from(p);  // the rays' origin
        if (!occluders.mayEnclose(from)) return false;  // skips the casts (none of them could find an inside)
        for (const float up : {1.0f, -1.0f}) {
            const glm::vec3 d(0.0f, 0.0f, up);
            const std::optional<RayCaster::Hit> hit =
                occluders.caster().intersect(from, d, 0.0f, std::numeric_limits<float>::infinity());
            if (!hit || !occluders.closed(hit->triangle) || !(glm::dot(hit->normal, d) > 0.0f)) return false;
        }
        return true;
    }

    long steps = 0;  // tracking steps so far (density lookups), all paths and shadow rays: what a path costs

  private:

    // One camera path of sample(); kMixed: as `mixed` renders it (compiled apart, so that the reference's paths
    // pay nothing for the option).
    template <bool kMixed>
    Rgb walk(const Ray &camera, Rng &rng, bool unscattered, MixedRender *mixed) {
        glm::dvec3 p = camera.origin, d = camera.direction;
        Rgb throughput(1.0), radiance(0.0);
        bool first = true;
        for (long event = 0; event < kMaxEvents; ++event) {
            // The next collision ignoring surfaces, then the first surface before it: the same as tracking
            // up to the surface (free flights are memoryless), and most flights in snow are short.
            const float tNear = first ? 0.0f : float(kSurfaceEpsilon);
            double tCollision = sampleCollision(p, d, kInfinity, rng);
            std::optional<RayCaster::Hit> hit;
            if (tCollision == kInfinity || scene_.occluders->caster().occluded(glm::vec3(p), glm::vec3(d), tNear, float(tCollision))) {
                hit = scene_.occluders->caster().intersect(glm::vec3(p), glm::vec3(d), tNear,
                                                           tCollision == kInfinity ? std::numeric_limits<float>::infinity() : float(tCollision));
                if (hit) tCollision = kInfinity;
            }
            const double tSurface = hit ? double(hit->distance) : kInfinity;
            if (tCollision < kInfinity) {
                p += tCollision * d;
                if constexpr (kMixed) {
                    if (!first) radiance += throughput * mixed->emittedAt(p, -d);
                    const double share = mixed->scatterShare(p);
                    if (share <= 0.0) return radiance;
                    throughput *= share;
                }
                throughput *= medium_.optics().albedo;
                radiance += throughput * lightScattered(p, d, rng);
                if constexpr (kMixed) {
                    if (event >= mixed->bounces) return radiance;
                }
                d = sampleHenyeyGreenstein(d, medium_.optics().g, rng.uniform(), rng.uniform());
            } else if (hit) {
                if (first && !unscattered) return radiance;  // a surface in front of the snow: the renderer draws it
                p += tSurface * d;
                const glm::dvec3 n = glm::dot(glm::dvec3(hit->normal), d) < 0.0 ? glm::dvec3(hit->normal)
                                                                                  : -glm::dvec3(hit->normal);
                throughput *= scene_.occluders->albedo(hit->triangle);
                radiance += throughput * lightReflected(p, n, rng);
                d = sampleCosineHemisphere(n, rng.uniform(), rng.uniform());
            } else {
                if (!first || unscattered) radiance += throughput * scene_.sky.radianceFrom(d);
                return radiance;
            }
            first = false;
            // Russian roulette once the path carries little: unbiased, and it ends absorbing paths.
            const double q = maxComponent(throughput);
            if (q < 0.25) {
                if (rng.uniform() >= q) return radiance;
                throughput /= q;
            }
        }
        return radiance;
    }

    // Delta tracking: distance to the first real collision before tEnd, or infinity. With `skipEmpty`, a
    // tentative collision in a block without snow jumps to where the ray leaves the block (none of the block's
    // tentative collisions could be real, and free flights are memoryless: the same distribution).
    double sampleCollision(const glm::dvec3 &p, const glm::dvec3 &d, double tEnd, Rng &rng) {
        double t0, t1;
        if (!medium_.clipToBounds(p, d, t0, t1)) return kInfinity;
        t1 = std::min(t1, tEnd);
        for (double t = t0;;) {
            ++steps;
            t -= std::log(1.0 - rng.uniform()) / sigmaBar_;
            if (t >= t1) return kInfinity;
            if (skipEmpty_) {
                if (const double exit = emptyBlockExit(p, d, t); exit > t) {
                    t = exit;
                    continue;
                }
            }
            if (rng.uniform() * sigmaBar_ < sigmaT(p + t * d)) return t;
        }
    }

    // Where the ray p + t d leaves the empty aligned block (Medium::emptyBlockEdge) that holds p + t d, or t if that
    // point's block holds snow.
    double emptyBlockExit(const glm::dvec3 &p, const glm::dvec3 &d, double t) {
        const glm::dvec3 ijk = medium_.worldToIndex(p + t * d);
        const openvdb::Coord cell(int(std::floor(ijk.x)), int(std::floor(ijk.y)), int(std::floor(ijk.z)));
        const int edge = medium_.emptyBlockEdge(cell, support_);
        if (edge == 0) return t;
        double exit = kInfinity;
        for (int a = 0; a < 3; ++a) {
            const double low = double(cell[a] & ~(edge - 1));  // blocks are aligned to their edge
            if (d[a] > 0.0) exit = std::min(exit, (low + edge - ijk[a]) / d[a]);
            else if (d[a] < 0.0) exit = std::min(exit, (low - ijk[a]) / d[a]);
        }
        return t + exit * medium_.voxelSize() + 1e-9;
    }

    // Ratio tracking with Russian roulette: unbiased transmittance of the medium from p along d, up to tEnd.
    double transmittance(const glm::dvec3 &p, const glm::dvec3 &d, double tEnd, Rng &rng) {
        double t0, t1;
        if (!medium_.clipToBounds(p, d, t0, t1)) return 1.0;
        t1 = std::min(t1, tEnd);
        double T = 1.0;
        for (double t = t0;;) {
            ++steps;
            t -= std::log(1.0 - rng.uniform()) / sigmaBar_;
            if (t >= t1) return T;
            if (skipEmpty_) {
                if (const double exit = emptyBlockExit(p, d, t); exit > t) {
                    t = exit;
                    continue;
                }
            }
            T *= 1.0 - sigmaT(p + t * d) / sigmaBar_;
            if (T < 0.1) {
                if (rng.uniform() >= T * 10.0) return 0.0;
                T = 0.1;
            }
        }
    }

    // Light of sun or lamp b (the suns, then the lamps) arriving at p from one sampled point of it:
    // irradiance * visibility * transmittance, with the direction towards that point in `towards`.
    Rgb lightIrradiance(std::size_t b, const glm::dvec3 &p, double offset, glm::dvec3 &towards, Rng &rng) {
        const double u1 = rng.uniform(), u2 = rng.uniform();
        Rgb E;
        double distance = kInfinity;
        if (b < scene_.suns.size()) {
            towards = sampleSunDirection(scene_.suns[b], u1, u2);
            E = scene_.suns[b].irradiance;
        } else {
            const LampSample lamp = sampleLamp(scene_.lamps[b - scene_.suns.size()], p, u1, u2);
            towards = lamp.direction, E = lamp.irradiance, distance = lamp.distance;
        }
        if (E == Rgb(0.0)) return E;
        const float far = distance == kInfinity ? std::numeric_limits<float>::infinity() : float(distance * (1.0 - 1e-6));
        if (scene_.occluders->caster().occluded(glm::vec3(p), glm::vec3(towards), float(offset), far)) return Rgb(0.0);
        return E * transmittance(p, towards, distance, rng);
    }

    std::size_t lightCount() const { return scene_.suns.size() + scene_.lamps.size(); }

    // Single scattering of the lights at a medium collision, towards -d (the camera side of the path).
    Rgb lightScattered(const glm::dvec3 &p, const glm::dvec3 &d, Rng &rng) {
        Rgb sum(0.0);
        for (std::size_t b = 0; b < lightCount(); ++b) {
            glm::dvec3 w;
            const Rgb E = lightIrradiance(b, p, 0.0, w, rng);
            // Light travels along -w and leaves along -d: the scattering cosine is dot(w, d).
            if (E != Rgb(0.0)) sum += E * henyeyGreenstein(glm::dot(w, d), medium_.optics().g);
        }
        return sum;
    }

    // The lights reflected by a Lambertian surface with normal n (albedo applied by the caller).
    Rgb lightReflected(const glm::dvec3 &p, const glm::dvec3 &n, Rng &rng) {
        Rgb sum(0.0);
        for (std::size_t b = 0; b < lightCount(); ++b) {
            glm::dvec3 w;
            const Rgb E = lightIrradiance(b, p, kSurfaceEpsilon, w, rng);
            sum += E * std::max(0.0, glm::dot(n, w)) / kPi;
        }
        return sum;
    }

    bool skipEmpty_;
    const Scene &scene_;
    const Medium &medium_;
    Medium::DensitySampler density_;  // tracking reads each cell many times
    Medium::SupportAccessor support_;
    double k_, sigmaBar_;
    const SourceDirections &directions_;  // where the source is gathered besides its moments (sourceIn)
};

namespace {
// The mean of `samples` radiance samples and its standard error, from their sum and sum of squares.
RadianceEstimate meanOf(const Rgb &sum, const Rgb &sumSquares, int samples) {
    RadianceEstimate out;
    const double n = std::max(samples, 1);
    out.mean = sum / n;
    const Rgb variance = glm::max(sumSquares / n - out.mean * out.mean, Rgb(0.0));
    out.standardError = glm::sqrt(variance / std::max(n - 1.0, 1.0));
    return out;
}
}  // namespace

MonteCarloReference::MonteCarloReference(Scene scene)
    : scene_(std::move(scene)), directions_(sourceDirections(brightestBeam(scene_))) {
    validate(scene_);
}

namespace {
// The mean radiance of `samples` paths along `ray` drawn from rng; `mixed`: none (the reference's paths) or the
// MixedRender they are rendered by.
template <class... Mixed>
RadianceEstimate meanRadiance(PathTracer &tracer, const Ray &ray, int samples, Rng &rng, Mixed &...mixed) {
    Rgb sum(0.0), sumSquares(0.0);
    for (int s = 0; s < samples; ++s) {
        const Rgb L = tracer.sample(ray, rng, mixed...);
        sum += L, sumSquares += L * L;
    }
    return meanOf(sum, sumSquares, samples);
}

// Distance (m) along a camera ray to the first occluder, infinity if none.
double surfaceDistance(const Scene &scene, const Ray &ray) {
    const auto hit = scene.occluders->caster().intersect(glm::vec3(ray.origin), glm::vec3(ray.direction));
    return hit ? double(hit->distance) : kInfinity;
}

// Rays in parallel, ray i's paths drawn from stream i of `seed` (deterministic), one path tracer per thread: the
// reference's estimates, or with `perThread` the mixed render's (each thread's MixedRender its own).
std::vector<RadianceEstimate> estimateRays(const MonteCarloReference &reference, const std::vector<Ray> &rays,
                                           int samplesPerRay, std::uint64_t seed, Progress *progress,
                                           const std::function<MixedRender()> *perThread) {
    std::vector<RadianceEstimate> out(rays.size());
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 1), [&](const auto &range) {
        PathTracer tracer(reference);
        std::optional<MixedRender> mixed;
        if (perThread) mixed = (*perThread)();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (progress) progress->throwIfCancelled();
            Rng rng(seed, i);
            if (!mixed) {
                out[i] = meanRadiance(tracer, rays[i], samplesPerRay, rng);
            } else {
                out[i] = meanRadiance(tracer, rays[i], samplesPerRay, rng, *mixed);
                out[i].mean += mixed->emittedAlong(rays[i], surfaceDistance(reference.scene(), rays[i]));
            }
            if (progress) progress->report(double(++done) / rays.size());
        }
    });
    return out;
}
}  // namespace

RadianceEstimate MonteCarloReference::estimate(const Ray &ray, int samples, std::uint64_t seed,
                                               std::uint64_t stream) const {
    PathTracer tracer(*this);
    Rng rng(seed, stream);
    return meanRadiance(tracer, ray, samples, rng);
}

PhotonTracer::PhotonTracer(const MonteCarloReference &reference)
    : tracer_(std::make_unique<PathTracer>(reference, true)) {}

PhotonTracer::~PhotonTracer() = default;

void PhotonTracer::follow(const Photon &photon, const glm::dvec3 &boxMin, const glm::dvec3 &boxMax, Rng &rng,
                          const CollisionTally &tally) {
    tracer_->follow(photon, boxMin, boxMax, rng, tally);
}

Rgb PhotonTracer::radianceArriving(const Ray &ray, Rng &rng) { return tracer_->sample(ray, rng, true); }

long PhotonTracer::steps() const { return tracer_->steps; }

bool PhotonTracer::enclosed(const glm::dvec3 &p) const { return tracer_->enclosed(p); }

SourceEstimate MonteCarloReference::sourceIn(const openvdb::Coord &voxel, int samples, std::uint64_t seed,
                                             std::uint64_t stream, Gathering how, const SubProgress &progress) const {
    const bool scattered = how != Gathering::BeamsOnly;
    PathTracer tracer(*this, !scattered);  // the per-voxel gathering's draws as they were (bench/bake_suite.py)
    Rng rng(seed, stream);
    const Medium &medium = *scene_.medium;
    const glm::dvec3 centre = medium.voxelCentre(voxel);
    // Points spread over the voxel, each weighted by its extinction: the renderer draws sigma_t S, so the
    // voxel's S is the extinction-weighted mean of the light's (the fluence falls steeply in thick voxels).
    ArrivingLight sum;
    ArrivingToward toward;
    double weights = 0.0;
    KroneckerSequence points(rng);
    // Where cameras see a thick voxel: points drawn so, of equal weight (VisiblePoints).
    std::vector<glm::dvec3> seen;
    long seenSteps = 0;  // their draws' work (the bake's budget counts it: planGathering)
    if (how == Gathering::WhereSeen) {
        KroneckerSequence candidates(rng);
        seen = visiblePoints(medium, voxel, directions_, samples, threeOf(candidates), rng, seenSteps);
    }
    WorkCheck work(progress);
    long counted = 0;
    for (int s = 0; s < samples; ++s) {
        work.add(stepsSince(tracer.steps, counted));
        const std::array<double, 5> u = points.next();
        const glm::dvec3 p = seen.empty() ? centre + medium.voxelSize() * (glm::dvec3(u[0], u[1], u[2]) - 0.5) : seen[s];
        const double w = seen.empty() ? tracer.sigmaT(p) : 1.0;
        if (w <= 0.0 || tracer.enclosed(p)) continue;  // cameras never see inside an occluder
        tracer.sampleArriving(p, w, u[3], u[4], rng, sum, toward, scattered);
        weights += w;
    }
    SourceEstimate out = sourceOf(sum, &toward, weights, medium.optics());
    out.steps = tracer.steps + seenSteps;
    return out;
}

namespace {

// The density of a camera ray's collisions at optical depth `depth` along a face's normal, the ray at mu to the
// normal and stopped within the normal's optical depth `chord` (facePoints).
double collisionDensity(double depth, double chord, double mu) {
    return std::exp(-depth / mu) / (mu * -std::expm1(-chord / mu));
}

// The same over facePoints' mu, cosine-weighted: the integral of 2 mu collisionDensity over mu (smooth, at most
// 2 / (1 - exp(-chord))), by the midpoint rule.
double drawnDensity(double depth, double chord) {
    constexpr int kNodes = 32;
    double sum = 0.0;
    for (int i = 0; i < kNodes; ++i) {
        const double mu = (i + 0.5) / kNodes;
        sum += 2.0 * mu * collisionDensity(depth, chord, mu);
    }
    return sum / kNodes;
}

}  // namespace

FaceEstimate MonteCarloReference::faceSourceIn(const openvdb::Coord &voxel, int face, int samples,
                                               std::uint64_t seed, std::uint64_t stream,
                                               const SubProgress &progress) const {
    PathTracer tracer(*this, false);
    Rng rng(seed, stream);
    const Medium &medium = *scene_.medium;
    KroneckerSequence points(rng), candidates(rng);
    long seenSteps = 0;
    const std::vector<FacePoint> seen = facePoints(medium, voxel, face, samples, threeOf(candidates), seenSteps);
    // Each point's light split by the hat: the air neighbour's share to what it carries, the voxel's to what
    // the voxel shows this face's cameras (one path each). Towards a direction leaving through the face at mu to
    // its normal, the points reweighted to that camera's collisions (collisionDensity over the points' own, the
    // mixture of facePoints' mu).
    const glm::dvec3 normal = faceNormal(face);
    std::array<double, kSourceDirections> mu{};
    for (int k = 0; k < kSourceDirections; ++k) mu[k] = glm::dot(directions_[k], normal);
    ArrivingLight carried, shown;
    ArrivingToward carriedToward, shownToward;
    std::array<double, kSourceDirections> carriedTowardWeights{}, shownTowardWeights{};
    double carriedWeights = 0.0, shownWeights = 0.0;
    WorkCheck work(progress);
    long counted = 0;
    for (const FacePoint &p : seen) {
        work.add(stepsSince(tracer.steps, counted));
        const std::array<double, 5> u = points.next();
        if (tracer.enclosed(p.p)) continue;
        ArrivingLight one;
        ArrivingToward oneToward;
        tracer.sampleArriving(p.p, 1.0, u[3], u[4], rng, one, oneToward, true);
        const double air = 1.0 - p.voxelShare;
        carried.addScaled(one, air), shown.addScaled(one, p.voxelShare);
        carriedWeights += air, shownWeights += p.voxelShare;
        const double drawn = drawnDensity(p.depth, p.chord);
        for (int k = 0; k < kSourceDirections; ++k) {
            const double w = mu[k] > 0.0 ? collisionDensity(p.depth, p.chord, mu[k]) / drawn : 1.0;
            carriedToward.toward[k] += w * air * oneToward.toward[k];
            shownToward.toward[k] += w * p.voxelShare * oneToward.toward[k];
            carriedTowardWeights[k] += w * air, shownTowardWeights[k] += w * p.voxelShare;
        }
    }
    for (int k = 0; k < kSourceDirections; ++k) {  // sourceOf divides by the weights of the moments
        if (carriedTowardWeights[k] > 0.0) carriedToward.toward[k] *= carriedWeights / carriedTowardWeights[k];
        if (shownTowardWeights[k] > 0.0) shownToward.toward[k] *= shownWeights / shownTowardWeights[k];
    }
    FaceEstimate out{sourceOf(carried, &carriedToward, carriedWeights, medium.optics()),
                     sourceOf(shown, &shownToward, shownWeights, medium.optics()),
                     shownWeights / std::max(carriedWeights + shownWeights, 1e-300)};
    out.carried.steps = tracer.steps + seenSteps;
    return out;
}

SourceEstimate sourceOf(const ArrivingLight &sum, const ArrivingToward *toward, double weights,
                        const VolumeOptics &optics) {
    SourceEstimate out;
    if (weights <= 0.0) return out;
    for (int c = 0; c < 3; ++c) {
        const double scale = optics.albedo[c] * kInvFourPi / weights;
        out.beamL0[c] = scale * sum.phiBeam[c];
        out.beamL1[c] = 3.0 * optics.g * scale * sum.fluxBeam[c];
        out.l0[c] = scale * sum.phi[c] + out.beamL0[c];
        out.l1[c] = 3.0 * optics.g * scale * sum.flux[c] + out.beamL1[c];
    }
    const double greyScale = kInvFourPi / weights;
    out.second = greyScale * sum.second;
    for (int i = 0; i < 3; ++i) out.third[i] = greyScale * sum.third[i];
    if (toward)
        for (int j = 0; j < kSourceDirections; ++j) out.toward[j] = toward->toward[j] / weights;
    return out;
}

glm::dvec3 brightestBeam(const Scene &scene) {
    glm::dvec3 travel(0.0);
    double brightest = 0.0;
    for (const SunLight &sun : scene.suns)
        if (const double E = glm::dot(sun.irradiance, Rgb(1.0)); E > brightest) brightest = E, travel = -sun.direction;
    return travel;
}

SourceDirections sourceDirections(const glm::dvec3 &beamTravel) {
    SourceDirections out;
    int n = 0;
    for (int x = -1; x <= 1; ++x)
        for (int y = -1; y <= 1; ++y)
            for (int z = -1; z <= 1; ++z)
                if (x || y || z) out[n++] = glm::normalize(glm::dvec3(x, y, z));
    const glm::dvec3 axis = beamTravel == glm::dvec3(0.0) ? glm::dvec3(0.0, 0.0, 1.0) : beamTravel;
    out[n++] = axis;
    for (const double degrees : {10.0, 25.0})
        for (int i = 0; i < 6; ++i) out[n++] = directionAround(axis, std::cos(degrees * kPi / 180.0), kPi * i / 3.0);
    return out;
}

namespace {
// What the snow scatters of `fluence`, the channels' mean.
double greyScattered(const Rgb &fluence, const VolumeOptics &optics) { return glm::dot(optics.albedo, fluence) / 3.0; }
}  // namespace

void ArrivingLight::add(const Rgb &fluence, const glm::dvec3 &travel, bool beam, const VolumeOptics &optics) {
    (beam ? phiBeam : phi) += fluence;
    glm::dmat3 &toFlux = beam ? fluxBeam : flux;
    for (int c = 0; c < 3; ++c) toFlux[c] += fluence[c] * travel;
    const glm::dmat3 tt = greyScattered(fluence, optics) * glm::outerProduct(travel, travel);
    second += tt;
    for (int i = 0; i < 3; ++i) third[i] += travel[i] * tt;
}

void ArrivingLight::addScaled(const ArrivingLight &o, double w) {
    phi += w * o.phi, phiBeam += w * o.phiBeam, flux += w * o.flux, fluxBeam += w * o.fluxBeam, second += w * o.second;
    for (int i = 0; i < 3; ++i) third[i] += w * o.third[i];
}

ArrivingLight &ArrivingLight::operator+=(const ArrivingLight &o) {
    phi += o.phi, phiBeam += o.phiBeam, flux += o.flux, fluxBeam += o.fluxBeam, second += o.second;
    for (int i = 0; i < 3; ++i) third[i] += o.third[i];
    return *this;
}

void ArrivingToward::add(const Rgb &fluence, const glm::dvec3 &travel, const VolumeOptics &optics,
                         const SourceDirections &directions) {
    const double grey = greyScattered(fluence, optics);
    for (int j = 0; j < kSourceDirections; ++j) toward[j] += grey * henyeyGreenstein(glm::dot(travel, directions[j]), optics.g);
}

void ArrivingToward::addScaled(const ArrivingToward &o, double w) {
    for (int j = 0; j < kSourceDirections; ++j) toward[j] += w * o.toward[j];
}

ArrivingToward &ArrivingToward::operator+=(const ArrivingToward &o) {
    for (int j = 0; j < kSourceDirections; ++j) toward[j] += o.toward[j];
    return *this;
}

SourceEstimate &operator+=(SourceEstimate &a, const SourceEstimate &b) {
    a.l0 += b.l0, a.l1 += b.l1, a.beamL0 += b.beamL0, a.beamL1 += b.beamL1, a.second += b.second;
    for (int i = 0; i < 3; ++i) a.third[i] += b.third[i];
    for (int j = 0; j < kSourceDirections; ++j) a.toward[j] += b.toward[j];
    a.steps += b.steps;
    return a;
}

std::vector<RadianceEstimate> MonteCarloReference::estimate(const std::vector<Ray> &rays, int samplesPerRay,
                                                            std::uint64_t seed, Progress *progress) const {
    if (progress) progress->report(0.0, "Monte Carlo reference");
    return estimateRays(*this, rays, samplesPerRay, seed, progress, nullptr);
}

std::vector<RadianceEstimate> estimateMixed(const MonteCarloReference &reference, const std::vector<Ray> &rays,
                                            int samplesPerRay, std::uint64_t seed,
                                            const std::function<MixedRender()> &perThread) {
    return estimateRays(reference, rays, samplesPerRay, seed, nullptr, &perThread);
}

}  // namespace firn
