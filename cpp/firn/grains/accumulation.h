#pragma once

// Where grains of snow come to rest: Chrisman's accumulation model ("Rendering Realistic Snow", 2008).
// Grains fall along straight rays from random points above the scene; where a ray first meets a triangle or a
// grain already lying there, and that surface is not too steep, a new grain is placed touching it:
//   centre = hit + r_new * n,   n the unit normal at the hit (the grain's own normal for a grain hit),
// so grains stack on grains. Steep hits are discarded, as are grains that would overlap what is there.
#include <cstddef>
#include <cstdint>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"
#include "firn/grains/grain_set.h"
#include "firn/util/progress.h"

namespace firn {

// Grains may overlap a neighbour by at most this fraction of the smaller radius, and a triangle by this
// fraction of their radius (m / m). Placing a grain exactly tangent leaves only rounding; the tolerance is
// what a new grain that also touches a third one may press into it.
inline constexpr double kGrainOverlapTolerance = 0.01;

// The most grains one call makes: about 100 bytes each while accumulating (2 GB).
inline constexpr std::size_t kMaxGrainCount = 20'000'000;

struct AccumulationSettings {
    std::size_t count = 1000;            // grains to place
    double radius = 1e-3;                // m, mean grain radius r
    double radiusVariation = 0.0;        // sigma in [0, 1): radius r (1 + sigma u), u uniform in [-1, 1]
    glm::dvec3 direction{0.0, 0.0, -1.0};  // snowfall direction (normalized here)
    double maxSlope = 1.0471975511965976;  // rad (60 deg): the steepest surface a grain stays on
    std::uint64_t seed = 0;
    std::size_t maxRays = 0;             // rays to try before giving up; 0: 20 count + 10000
};

struct AccumulationResult {
    GrainSet grains;
    std::size_t rays = 0;         // rays cast
    std::size_t missed = 0;       // rays that met nothing
    std::size_t steep = 0;        // rays whose hit was steeper than maxSlope
    std::size_t overlapping = 0;  // grains discarded because they would overlap a grain or a triangle
};

// InvalidArgument for settings that are not a snowfall (negative radius, sigma >= 1, zero direction, ...);
// BudgetExceeded for more than kMaxGrainCount grains.
void validate(const AccumulationSettings &settings);

// Places settings.count grains on the triangles (m, world space), or fewer if maxRays run out (the result
// says why). Deterministic for a seed, whatever the thread count. Reports to and honours `progress`.
AccumulationResult accumulateGrains(const TriangleMesh &mesh, const AccumulationSettings &settings,
                                    Progress *progress = nullptr);

}  // namespace firn
