#include "firn/grains/grain_pile.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "firn/util/error.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr double kAssumedVolumeFraction = 0.25;  // about what accumulation packs: turns a depth into a count

// A square box of side w, open at the top, walls of height h (m).
TriangleMesh openBox(double w, double h) {
    const float W = static_cast<float>(w), H = static_cast<float>(h);
    const std::vector<float> corners = {0, 0, 0, W, 0, 0, W, W, 0, 0, W, 0,   // floor
                                        0, 0, H, W, 0, H, W, W, H, 0, W, H};  // rim
    const std::vector<unsigned> triangles = {0, 1, 2, 0, 2, 3,                 // floor, facing up
                                             0, 4, 5, 0, 5, 1, 1, 5, 6, 1, 6, 2,  // walls
                                             2, 6, 7, 2, 7, 3, 3, 7, 4, 3, 4, 0};
    return makeTriangleMesh(corners.data(), 8, triangles.data(), triangles.size() / 3);
}

}  // namespace

GrainPile buildGrainPile(const PileSettings &s, Progress *progress) {
    if (!(s.radius > 0.0) || !(s.width > 4.0 * s.radius) || !(s.depth > 0.0) || !std::isfinite(s.width + s.depth))
        throw InvalidArgument("a grain pile needs radius > 0, a box wider than 4 radii and a depth > 0 (m)");
    const double grainVolume = 4.0 / 3.0 * kPi * s.radius * s.radius * s.radius;  // m^3, at the mean radius
    const double count = kAssumedVolumeFraction * s.width * s.width * s.depth / grainVolume;
    if (count > double(kMaxGrainCount))
        throw BudgetExceeded("a pile this deep and wide needs about " + std::to_string(std::llround(count)) +
                             " grains, more than the limit of " + std::to_string(kMaxGrainCount));
    GrainPile pile;
    pile.width = s.width;
    pile.box = openBox(s.width, 3.0 * s.depth + 4.0 * s.radius);  // walls well above the grains
    AccumulationSettings a;
    a.count = std::max<std::size_t>(1, static_cast<std::size_t>(count));
    a.radius = s.radius;
    a.radiusVariation = s.radiusVariation;
    a.seed = s.seed;
    a.maxRays = 50 * a.count + 10000;  // rays beside the box miss; overlaps are discarded
    pile.accumulation = accumulateGrains(pile.box, a, progress);
    const GrainSet &g = pile.accumulation.grains;
    for (std::size_t i = 0; i < g.size(); ++i) pile.top = std::max(pile.top, g.centres[i].z + g.radii[i]);
    return pile;
}

double pileVolumeFraction(const GrainPile &pile, double margin, double zLow, double zHigh) {
    const double lo = margin, hi = pile.width - margin;
    if (!(hi > lo) || !(zHigh > zLow)) throw InvalidArgument("the measured region of the pile is empty");
    const GrainSet &g = pile.accumulation.grains;
    double iceVolume = 0.0;  // m^3
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::dvec3 &c = g.centres[i];
        if (c.x >= lo && c.x <= hi && c.y >= lo && c.y <= hi && c.z >= zLow && c.z <= zHigh)
            iceVolume += 4.0 / 3.0 * kPi * g.radii[i] * g.radii[i] * g.radii[i];
    }
    return iceVolume / ((hi - lo) * (hi - lo) * (zHigh - zLow));
}

PileAlbedo measurePileAlbedo(const GrainPile &pile, double eta, const Rgb &iceAbsorption, const Rgb &groundAlbedo,
                             std::size_t paths, std::uint64_t seed, Progress *progress, PileLight light) {
    if (paths == 0) throw InvalidArgument("the albedo needs at least one path");
    GrainMaterials materials;
    materials.eta = eta;
    materials.iceAbsorption = iceAbsorption;
    materials.skyRadiance = Rgb(1.0);
    materials.surfaces.assign(pile.box.triangleCount(), GrainSurface{Rgb(1.0), true});  // mirror walls
    materials.surfaces[0] = materials.surfaces[1] = GrainSurface{groundAlbedo, false};   // the floor
    const GrainTracer tracer(pile.box, pile.accumulation.grains, materials);

    std::vector<GrainRay> rays(paths);
    Rng rng(seed, 0x5EED);
    const double w = pile.width, start = pile.top + 1e-3 * w;
    for (GrainRay &r : rays) {
        const double x = w * (0.25 + 0.5 * rng.uniform());  // named: argument order is unspecified in C++
        const double y = w * (0.25 + 0.5 * rng.uniform());
        const glm::dvec3 origin(x, y, start);
        // Oblique paths may meet a wall above the pile: the mirror sends them on as into the mirrored pile.
        glm::dvec3 down(0.0, 0.0, -1.0);
        if (light == PileLight::Diffuse) {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            down = sampleCosineHemisphere(down, u1, u2);
        }
        r = GrainRay{origin, down};
    }
    PileAlbedo albedo;
    // One path per ray: the spread over rays is the spread of the albedo estimate.
    const std::vector<GrainRadiance> each = tracer.radiance(rays, 1, seed, progress, &albedo.stats);
    Rgb sum(0.0), sumSquares(0.0);
    for (const GrainRadiance &e : each) sum += e.mean, sumSquares += e.mean * e.mean;
    const double n = double(paths);
    albedo.mean = sum / n;
    const Rgb variance = glm::max(Rgb(0.0), sumSquares / n - albedo.mean * albedo.mean) * (n / std::max(1.0, n - 1.0));
    albedo.standardError = glm::sqrt(variance / n);
    return albedo;
}

}  // namespace firn
