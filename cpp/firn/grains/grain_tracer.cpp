#include "firn/grains/grain_tracer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "firn/optics/fresnel.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

double maxComponent(const Rgb &c) { return std::max({c.x, c.y, c.z}); }

bool isAlbedo(const Rgb &c) {
    return c.x >= 0.0 && c.y >= 0.0 && c.z >= 0.0 && c.x <= 1.0 && c.y <= 1.0 && c.z <= 1.0;
}

// Scene size (m) from triangles and grains, for the offset that keeps a bounced path off its own triangle.
double sceneExtent(const TriangleMesh &mesh, const GrainSet &grains) {
    double extent = 0.0;
    for (const glm::vec3 &p : mesh.positions) extent = std::max({extent, double(std::abs(p.x)), double(std::abs(p.y)), double(std::abs(p.z))});
    for (std::size_t i = 0; i < grains.size(); ++i) {
        const glm::dvec3 &c = grains.centres[i];
        extent = std::max({extent, std::abs(c.x) + grains.radii[i], std::abs(c.y) + grains.radii[i], std::abs(c.z) + grains.radii[i]});
    }
    return std::max(extent, 1e-6);
}

}  // namespace

GrainTracer::GrainTracer(const TriangleMesh &mesh, const GrainSet &grains, GrainMaterials materials)
    : mesh_(mesh), grains_(grains), materials_(std::move(materials)), triangles_(mesh),
      spheres_((validate(grains), grains)), epsilon_(1e-6 * sceneExtent(mesh, grains)) {
    if (!(materials_.eta > 1.0) || !std::isfinite(materials_.eta))
        throw InvalidArgument("ice refractive index must be a number above 1 (ice: 1.31)");
    const Rgb &a = materials_.iceAbsorption;
    if (!(a.x >= 0.0 && a.y >= 0.0 && a.z >= 0.0) || !std::isfinite(a.x + a.y + a.z))
        throw InvalidArgument("ice absorption must be three non-negative coefficients (1/m)");
    if (materials_.surfaces.empty()) materials_.surfaces.push_back(GrainSurface{});
    if (materials_.surfaces.size() != 1 && materials_.surfaces.size() != mesh.triangleCount())
        throw InvalidArgument("give one surface for all triangles or one per triangle (" +
                              std::to_string(mesh.triangleCount()) + "), not " + std::to_string(materials_.surfaces.size()));
    for (const GrainSurface &s : materials_.surfaces)
        if (!isAlbedo(s.albedo)) throw InvalidArgument("surface albedo must be three numbers in [0, 1]");
    const Rgb &sky = materials_.skyRadiance;
    if (!(sky.x >= 0.0 && sky.y >= 0.0 && sky.z >= 0.0) || !std::isfinite(sky.x + sky.y + sky.z))
        throw InvalidArgument("sky radiance must be three non-negative numbers (W/m^2/sr)");
    if (materials_.sun) {
        GrainSun &sun = *materials_.sun;
        if (!(glm::length(sun.direction) > 0.0)) throw InvalidArgument("sun direction must be a non-zero vector");
        sun.direction = glm::normalize(sun.direction);
        if (!(sun.angularRadius > 0.0 && sun.angularRadius < 0.5 * kPi))
            throw InvalidArgument("sun angular radius must be between 0 and 90 degrees");
    }
}

const GrainSurface &GrainTracer::surface(unsigned triangle) const {
    return materials_.surfaces.size() == 1 ? materials_.surfaces[0] : materials_.surfaces[triangle];
}

Rgb GrainTracer::escape(const glm::dvec3 &direction) const {
    Rgb radiance = materials_.skyRadiance;
    if (materials_.sun && glm::dot(direction, materials_.sun->direction) >= std::cos(materials_.sun->angularRadius))
        radiance += materials_.sun->radiance;
    return radiance;
}

Rgb GrainTracer::tracePath(const GrainRay &ray, Rng &rng, std::size_t &events) const {
    const double eta = materials_.eta;
    Rgb throughput(1.0);
    glm::dvec3 origin = ray.origin, direction = glm::normalize(ray.direction);
    long leftGrain = -1;  // the grain the path is leaving: not to be met again at distance 0
    // Russian roulette on throughput: survive with p = max channel (at most 1), weight divided by p. Unbiased.
    auto survives = [&]() {
        const double p = std::min(1.0, maxComponent(throughput));
        if (p >= 1.0) return true;
        if (p <= 0.0 || rng.uniform() >= p) return false;
        throughput /= p;
        return true;
    };

    for (events = 0; events < kMaxPathEvents;) {
        const auto triangle = triangles_.intersect(glm::vec3(origin), glm::vec3(direction));
        double tTriangle = std::numeric_limits<double>::infinity();
        glm::dvec3 nTriangle(0.0);
        if (triangle) {
            nTriangle = glm::normalize(glm::dvec3(mesh_.crossNormal(triangle->triangle)));
            const double along = glm::dot(direction, nTriangle);
            tTriangle = std::abs(along) > 1e-12 ? glm::dot(glm::dvec3(mesh_.vertex(triangle->triangle, 0)) - origin, nTriangle) / along
                                                : double(triangle->distance);
            if (along > 0.0) nTriangle = -nTriangle;  // facing the path
        }
        const auto grain = spheres_.intersect(origin, direction, tTriangle, leftGrain);
        ++events;

        if (!grain && !triangle) return throughput * escape(direction);

        if (!grain) {  // a triangle
            const GrainSurface &s = surface(triangle->triangle);
            throughput *= s.albedo;
            const glm::dvec3 hit = origin + tTriangle * direction;
            if (s.mirror) {
                direction = reflect(direction, nTriangle);
            } else {
                const double u1 = rng.uniform(), u2 = rng.uniform();  // named: argument order is unspecified
                direction = sampleCosineHemisphere(nTriangle, u1, u2);
            }
            origin = hit + epsilon_ * nTriangle;
            leftGrain = -1;
            if (!survives()) return Rgb(0.0);
            continue;
        }

        // An ice grain: reflect off it with Kr, or refract into it.
        const glm::dvec3 &centre = grains_.centres[grain->grain];
        const double radius = grains_.radii[grain->grain];
        glm::dvec3 hit = origin + grain->distance * direction;
        const double kr = fresnelReflectance(-glm::dot(direction, grain->normal), eta);
        leftGrain = grain->grain;
        if (rng.uniform() < kr) {
            direction = reflect(direction, grain->normal);
            origin = hit;
            continue;
        }
        direction = *refract(direction, grain->normal, eta);  // never total from the optically thinner side
        // Inside: chords from surface to surface until the path refracts out. In a sphere every internal
        // incidence equals the refraction angle, so total internal reflection cannot happen; it is handled anyway.
        for (;;) {
            const double chord = std::max(0.0, -2.0 * glm::dot(hit - centre, direction));  // m
            const Rgb &gamma = materials_.iceAbsorption;
            throughput *= Rgb(std::exp(-gamma.x * chord), std::exp(-gamma.y * chord), std::exp(-gamma.z * chord));
            hit += chord * direction;
            const glm::dvec3 outward = glm::normalize(hit - centre);
            hit = centre + radius * outward;  // back onto the sphere, so rounding never drifts inside or out
            ++events;
            if (!survives()) return Rgb(0.0);
            if (events >= kMaxPathEvents) return Rgb(0.0);
            const double krInside = fresnelReflectance(glm::dot(direction, outward), 1.0 / eta);
            if (rng.uniform() < krInside) {
                direction = reflect(direction, outward);
                continue;
            }
            direction = *refract(direction, -outward, 1.0 / eta);  // krInside < 1, so not total
            break;
        }
        origin = hit;
    }
    return Rgb(0.0);  // bailed out (counted by the caller: events == kMaxPathEvents)
}

std::vector<GrainRadiance> GrainTracer::radiance(const std::vector<GrainRay> &rays, int samples, std::uint64_t seed,
                                                 Progress *progress, GrainPathStats *stats) const {
    if (samples < 1) throw InvalidArgument("samples must be at least 1");
    for (const GrainRay &r : rays)
        if (!(glm::length(r.direction) > 0.0) || !std::isfinite(r.origin.x + r.origin.y + r.origin.z))
            throw InvalidArgument("rays need finite origins and non-zero directions");
    std::vector<GrainRadiance> result(rays.size());
    std::atomic<std::size_t> done{0}, bailedOut{0}, totalEvents{0};
    std::atomic<bool> cancelled{false};
    tbb::parallel_for(std::size_t(0), rays.size(), [&](std::size_t i) {
        if (cancelled.load() || (progress && progress->isCancelled())) {
            cancelled.store(true);
            return;
        }
        Rgb sum(0.0), sumSquares(0.0);
        std::size_t events = 0, localEvents = 0, localBailed = 0;
        for (int j = 0; j < samples; ++j) {
            if (progress && progress->isCancelled()) {  // between paths: a long one takes at most a second
                cancelled.store(true);
                return;
            }
            Rng rng(seed, std::uint64_t(i) * std::uint64_t(samples) + std::uint64_t(j));
            const Rgb value = tracePath(rays[i], rng, events);
            localEvents += events;
            if (events >= kMaxPathEvents) ++localBailed;
            sum += value, sumSquares += value * value;
        }
        const double n = samples;
        const Rgb mean = sum / n;
        const Rgb variance = glm::max(Rgb(0.0), (sumSquares / n - mean * mean)) * (n / std::max(1.0, n - 1.0));
        result[i] = GrainRadiance{mean, glm::sqrt(variance / n)};
        totalEvents += localEvents, bailedOut += localBailed;
        const std::size_t finished = ++done;
        if (progress && finished % 64 == 0) progress->report(double(finished) / double(rays.size()), "Tracing grains");
    });
    if (progress) progress->throwIfCancelled();
    if (cancelled.load()) throw Cancelled();
    if (stats) {
        stats->paths = rays.size() * std::size_t(samples);
        stats->bailedOut = bailedOut.load();
        stats->meanEvents = stats->paths ? double(totalEvents.load()) / double(stats->paths) : 0.0;
    }
    return result;
}

}  // namespace firn
