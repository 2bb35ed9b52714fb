#include "firn/transport/bake_snow_irradiance.h"

#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/baked_grids.h"
#include "firn/transport/monte_carlo.h"
#include "firn/util/sampling.h"

namespace firn::bake {

// Light that surface voxels receive from other snow across the air (a valley between bumps, the inside
// of a hollow): the baked snow's radiance along the sky rays that snow hides (W/m^2 onto each patch), read
// from the bake's values as its grids would hold them.
SnowIrradiance snowIrradiance(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                              const SourceValues &source, const MonteCarloVoxels &traced, const GridValues &values,
                              const SkyRays &rays, std::uint64_t seed, const SubProgress &progress) {
    SnowIrradiance out{SurfaceValues<glm::vec3>(topo.surfaceSlot, topo.surfaceVoxels(), glm::vec3(0.0f)), {}};
    out.aim = out.irradiance;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 256), [&](const auto &range) {
        progress.throwIfCancelled();
        Medium::ColumnMarcher marcher(*scene.medium);
        Medium::Accessor density = scene.medium->accessor();
        BakedValuesSampler baked(topo, source, traced, values);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!light.snowRays[i]) continue;
            const glm::dvec3 p = patchOutside(*scene.medium, topo, i, density);
            glm::dvec3 sum(0.0), towards(0.0);
            for (int k = 0; k < rays.count(); ++k) {
                if (!(light.snowRays[i] >> k & 1)) continue;
                const glm::dvec3 w = rays.direction(topo.patches[i].normal, k, seed, i);
                const auto hit = scene.occluders->caster().intersect(glm::vec3(p), glm::vec3(w), 1e-5f);
                const double tMax = hit ? double(hit->distance) : std::numeric_limits<double>::infinity();
                const glm::dvec3 radiance = bakedRadianceAlong(scene, marcher, baked, Ray{p, w}, tMax, 0.5);
                sum += radiance, towards += greyMoment(radiance, w);
            }
            out.irradiance.surface(i) = glm::vec3(kPi * sum / double(rays.count()));  // snowRays: a surface voxel
            out.aim.surface(i) = glm::vec3(kPi * towards / double(rays.count()));
        }
    });
    return out;
}

}  // namespace firn::bake
