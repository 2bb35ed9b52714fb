#include "firn/spray/spray_density.h"

#include "firn/snow/metaball_layout.h"

namespace firn {

SnowGrids rasterizeSpray(const SprayParticles &particles, double lumpDensity, const RasterSettings &raster,
                         const SubProgress &progress) {
    // Ground below every ball's reach (base = radius + a band, see snow_rasterizer.cpp finishLeaf): the level set is
    // the balls' iso-surface alone.
    const float belowReach = float(4.0 * raster.voxelSize);
    std::vector<Metaball> balls;
    for (const SprayParticle &p : particles)
        for (int b = 0; b < p.ballCount; ++b) {
            const glm::vec3 centre = glm::vec3(p.position) + p.ballOffset[b];
            balls.push_back({centre, p.ballRadius[b], {0.0f, 0.0f, 1.0f}, p.ballRadius[b] + belowReach, 0.0f});
        }
    RasterSettings uniform = raster;
    uniform.compaction = CompactionProfile{lumpDensity, lumpDensity, 0.0, 1.0};
    return rasterizeSnow(balls, uniform, progress);
}

}  // namespace firn
