#pragma once

// Chrisman's brute-force Monte Carlo over ice grains ("Rendering Realistic Snow", 2008): light meets smooth
// ice spheres and triangles. At each air-ice interface the path reflects with the Fresnel probability Kr and
// refracts otherwise (Russian roulette on the Fresnel split: unbiased, no weight changes); inside the ice it is
// attenuated by exp(-gamma l) per channel, gamma the absorption coefficient of ice (1/m), l the chord (m); at a
// triangle it bounces diffusely (Lambert, cosine sampled) with the triangle's albedo or mirrors; a path that
// leaves the scene takes the sky's radiance. Throughput is ended only by Russian roulette (unbiased); the
// event cap kMaxPathEvents is a counted bail-out that converged piles never reach.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"
#include "firn/geometry/ray_caster.h"
#include "firn/grains/grain_set.h"
#include "firn/grains/sphere_scene.h"
#include "firn/util/color.h"
#include "firn/util/progress.h"
#include "firn/util/random.h"

namespace firn {

// Interfaces and bounces per path before bail-out: 400 times the mean of the deepest validated pile (2,236),
// and what keeps a closed white room (whose paths never leave nor lose weight) from running for ever.
inline constexpr std::size_t kMaxPathEvents = 1'000'000;

struct GrainSurface {
    Rgb albedo{0.8};      // reflectance per channel
    bool mirror = false;  // specular mirror instead of Lambertian (the walls of a measurement box)
};

// A sun as a small disc of the sky: escaping paths that leave within its cone take its radiance. Shadow rays
// toward it cannot pass ice (a delta refraction), so it is not sampled explicitly: keep its cone not too small.
struct GrainSun {
    glm::dvec3 direction{0.0, 0.0, 1.0};  // toward the sun
    double angularRadius = 0.05;          // rad, half-angle of the disc
    Rgb radiance{0.0};                    // W/m^2/sr within the disc
};

struct GrainMaterials {
    double eta = kIceRefractiveIndex;     // ice over air
    Rgb iceAbsorption{0.0};               // 1/m per channel (iceAbsorptionRgb gives Warren & Brandt's)
    std::vector<GrainSurface> surfaces;   // one per triangle, or one for all (empty: default)
    Rgb skyRadiance{1.0};                 // W/m^2/sr, uniform over the sphere of directions
    std::optional<GrainSun> sun;
};

struct GrainRay {
    glm::dvec3 origin;     // m
    glm::dvec3 direction;  // unit
};

struct GrainRadiance {
    Rgb mean{0.0};           // W/m^2/sr
    Rgb standardError{0.0};  // of the mean
};

struct GrainPathStats {
    std::size_t paths = 0;
    std::size_t bailedOut = 0;        // paths stopped at kMaxPathEvents (should stay 0)
    double meanEvents = 0.0;          // interfaces and bounces per path
};

class GrainTracer {
  public:
    // InvalidArgument for bad grains, eta <= 1, negative absorption, albedo outside [0, 1] or a surface list
    // that matches neither one nor every triangle. Mesh and grains must outlive the tracer.
    GrainTracer(const TriangleMesh &mesh, const GrainSet &grains, GrainMaterials materials);

    // The radiance arriving at ray.origin from -ray.direction (one path).
    Rgb tracePath(const GrainRay &ray, Rng &rng, std::size_t &events) const;

    // `samples` paths per ray, in parallel; path j of ray i uses its own stream, so the result depends only on
    // the seed. Reports to and honours `progress`.
    std::vector<GrainRadiance> radiance(const std::vector<GrainRay> &rays, int samples, std::uint64_t seed,
                                        Progress *progress = nullptr, GrainPathStats *stats = nullptr) const;

  private:
    const GrainSurface &surface(unsigned triangle) const;
    Rgb escape(const glm::dvec3 &direction) const;

    const TriangleMesh &mesh_;
    const GrainSet &grains_;
    GrainMaterials materials_;
    RayCaster triangles_;
    SphereScene spheres_;
    double epsilon_;  // m: offset off a triangle after a bounce (1e-6 of the scene size: above float spacing)
};

}  // namespace firn
