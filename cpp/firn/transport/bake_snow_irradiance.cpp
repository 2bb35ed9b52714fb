#include "firn/transport/bake_snow_irradiance.h"

#include <algorithm>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/baked_grids.h"
#include "firn/transport/monte_carlo.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"
#include "firn/util/work_check.h"

namespace firn::bake {

namespace {

// The first occluder's radiance back along w from p: its albedo times one cosine-weighted ray from the hit, the
// baked snow along it, and where it meets another occluder, that one's reflected sun and sky through that snow.
glm::dvec3 sentBackAlong(const Scene &scene, Medium::ColumnMarcher &marcher, BakedValuesSampler &baked,
                         const glm::dvec3 &p, const glm::dvec3 &w, Rng &rng) {
    const auto hit = scene.occluders->caster().intersect(glm::vec3(p), glm::vec3(w), 1e-5f);
    if (!hit) return glm::dvec3(0.0);
    const glm::dvec3 facing(hit->normal);
    const glm::dvec3 n = glm::normalize(glm::faceforward(facing, w, facing));  // towards p
    const glm::dvec3 q = p + double(hit->distance) * w + 1e-5 * n;
    const glm::dvec3 v = sampleCosineHemisphere(n, rng.uniform(), rng.uniform());
    const auto next = scene.occluders->caster().intersect(glm::vec3(q), glm::vec3(v), 1e-5f);
    const double reach = next ? double(next->distance) : std::numeric_limits<double>::infinity();
    double through = 1.0;  // the snow's transmittance between the two occluders
    glm::dvec3 arriving(bakedRadianceAlong(scene, marcher, baked, Ray{q, v}, reach, 0.5, &through));
    if (next) {
        const glm::dvec3 other(next->normal);
        arriving += through * reflectedByOccluder(scene, q + double(next->distance) * v,
                                                  glm::normalize(glm::faceforward(other, v, other)),
                                                  scene.occluders->albedo(next->triangle), rng, marcher);
    }
    return glm::dvec3(scene.occluders->albedo(hit->triangle)) * arriving;
}

// The rank-th set bit of `bits`.
int nthRay(std::uint64_t bits, int rank) {
    for (; rank > 0; --rank) bits &= bits - 1;
    return __builtin_ctzll(bits);
}

// The snow's light that occluders send back along patch i's sky rays that met them, snow not hiding them (`met`;
// W/m^2/sr summed over those rays; `towards` gets its grey first moment from their mean direction): the ground
// under thrown snow, lit by the snow above it. The first solve's light holds the occluders' reflection of sun and
// sky only (reflectedByOccluder). kDraws of the rays, stratified over them, stand for all of them, intersected
// alone: the car's patches meet the body and the ground by the million.
glm::dvec3 occludersSendBack(const Scene &scene, Medium::ColumnMarcher &marcher, BakedValuesSampler &baked,
                             const SnowTopology &topo, const SkyRays &rays, std::uint64_t met, const glm::dvec3 &p,
                             std::uint64_t seed, std::size_t i, glm::dvec3 &towards) {
    constexpr int kDraws = 2;
    const int count = __builtin_popcountll(met);
    if (count == 0) return glm::dvec3(0.0);
    // The same draws every pass (the seed does not change with it): addBounceTail extrapolates from the differences
    // between passes, which a new draw's noise would swamp.
    Rng rng(seed ^ 0x0CC1ull, i);
    const glm::dvec3 &normal = topo.patches[i].normal;
    const int draws = std::min(kDraws, count);
    glm::dvec3 sum(0.0), mean(0.0);
    for (int d = 0; d < draws; ++d) {
        const int rank = std::min(int((d + rng.uniform()) / draws * count), count - 1);
        sum += sentBackAlong(scene, marcher, baked, p, rays.direction(normal, nthRay(met, rank), seed, i), rng);
    }
    for (std::uint64_t bits = met; bits; bits &= bits - 1)
        mean += rays.direction(normal, __builtin_ctzll(bits), seed, i) / double(count);
    const glm::dvec3 radiance = double(count) / draws * sum;
    towards += greyMoment(radiance, mean);
    return radiance;
}

}  // namespace

// Light that surface voxels receive from other snow across the air (a valley between bumps, the inside
// of a hollow): the baked snow's radiance along the sky rays that snow hides (W/m^2 onto each patch), read
// from the bake's values as its grids would hold them.
SnowIrradiance snowIrradiance(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                              const SourceValues &source, const MonteCarloVoxels &traced, const GridValues &values,
                              const SkyRays &rays, std::uint64_t seed, const SubProgress &progress) {
    SnowIrradiance out{SurfaceValues<glm::vec3>(topo.surfaceSlot, topo.surfaceVoxels(), glm::vec3(0.0f)), {}};
    out.aim = out.irradiance;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 256), [&](const auto &range) {
        Medium::ColumnMarcher marcher(*scene.medium);
        Medium::Accessor density = scene.medium->accessor();
        BakedValuesSampler baked(topo, source, traced, values);
        WorkCheck work(progress);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!light.snowRays[i] && !light.occluderRays[i]) continue;
            const SkyRays own = skyRaysAt(topo, i, rays.count(), light.skyLattice);
            work.add(WorkCheck::kVoxel * std::uint64_t(1 + own.count()));  // a ray marched about as a voxel's work
            const glm::dvec3 p = patchOutside(*scene.medium, topo, i, density);
            glm::dvec3 sum(0.0), towards(0.0);
            for (int k = 0; k < own.count(); ++k) {
                if (!((light.snowRays[i] >> k) & 1)) continue;
                const glm::dvec3 w = own.direction(topo.patches[i].normal, k, seed, i);
                const auto hit = scene.occluders->caster().intersect(glm::vec3(p), glm::vec3(w), 1e-5f);
                const double tMax = hit ? double(hit->distance) : std::numeric_limits<double>::infinity();
                const glm::dvec3 radiance = bakedRadianceAlong(scene, marcher, baked, Ray{p, w}, tMax, 0.5);
                sum += radiance, towards += greyMoment(radiance, w);
            }
            sum += occludersSendBack(scene, marcher, baked, topo, own, light.occluderRays[i], p, seed, i, towards);
            out.irradiance.surface(i) = glm::vec3(kPi * sum / double(own.count()));  // snowRays: a surface voxel
            out.aim.surface(i) = glm::vec3(kPi * towards / double(own.count()));
        }
    });
    fillFromSkyDonors(topo, light.fromDonors, out.irradiance, false);
    fillFromSkyDonors(topo, light.fromDonors, out.aim, true);
    return out;
}

}  // namespace firn::bake
