// Sun and sky light reaching the snow (incident_light.h): the sky's probe rays.
#include "firn/transport/incident_light.h"

#include <gtest/gtest.h>

#include "firn/transport/slab.h"
#include "firn/util/openvdb_library.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.01;  // m

// A slab of snow 16 x 16 voxels wide and 4 deep under a sky brighter towards the horizon along +x (so that
// rays in different directions bring different radiance), optionally under a roof 20 cm above it that hides
// the whole sky from its top.
Scene slabUnderSky(bool roof) {
    initializeOpenVdb();
    Scene scene;
    scene.medium = std::make_shared<Medium>(makeSlabDensity(kVoxel, 16, 4, 300.0f), VolumeOptics{2.0, Rgb(0.999), 0.85});
    std::vector<Rgb> pixels(16 * 8);
    for (int row = 0; row < 8; ++row)
        for (int column = 0; column < 16; ++column) pixels[std::size_t(row * 16 + column)] = Rgb(1.0 + 0.2 * column, 1.0 + row, 2.0);
    scene.sky.radiance = Rgb(1.0);
    scene.sky.map = std::make_shared<EnvironmentMap>(16, 8, std::move(pixels));
    if (roof) {
        const float v[] = {-100, -100, 0.2f, 100, -100, 0.2f, 100, 100, 0.2f, -100, 100, 0.2f};
        const unsigned t[] = {0, 1, 2, 0, 2, 3};
        scene.occluders = std::make_shared<Occluders>(makeTriangleMesh(v, 4, t, 2), std::vector<Rgb>(2, Rgb(0.5)));
    }
    return scene;
}

IncidentLight skyLight(const Scene &scene, const SnowTopology &topology, bool probed) {
    IncidentLightSettings settings;
    settings.skySamples = 9, settings.seed = 7, settings.skyProbed = probed;
    return computeIncidentLight(scene, topology, settings, SubProgress(nullptr, 0.0, 1.0));
}

}  // namespace

// One probe per band of elevation and per band of azimuth (the strata's diagonal), and the whole grazing band,
// where occluders beside the snow are met first.
TEST(SkyRays, ProbesCoverEveryBandAndTheGrazingOnes) {
    for (int samples : {1, 4, 9, 16, 64}) {
        const SkyRays rays(samples);
        const int strata = rays.strata();
        std::vector<int> perRow(strata, 0), perColumn(strata, 0);
        for (int k = 0; k < rays.count(); ++k)
            if (rays.isProbe(k)) ++perRow[k / strata], ++perColumn[k % strata];
        for (int j = 0; j < strata; ++j) {
            EXPECT_GE(perRow[j], 1) << samples << " rays, elevation band " << j;
            EXPECT_GE(perColumn[j], 1) << samples << " rays, azimuth band " << j;
        }
        EXPECT_EQ(perRow[strata - 1], strata) << samples << " rays: the grazing band is probed whole";
    }
    EXPECT_EQ(SkyRays(9).count(), 9);
    for (int k : {1, 2, 3, 5}) EXPECT_FALSE(SkyRays(9).isProbe(k)) << k;
}

// Probing changes nothing where its assumption holds or where the probes meet anything: under open sky the
// slab's top (rays meet neither snow nor occluder) and under a roof (every probe meets it, so every ray is
// traced) get the same sky light, bit for bit, and the same rays hidden by snow, as tracing every ray.
TEST(SkyRays, ProbedSkyIsTheTracedSkyUnderOpenSkyAndUnderARoof) {
    for (bool roof : {false, true}) {
        const Scene scene = slabUnderSky(roof);
        const SnowTopology topology = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
        const IncidentLight traced = skyLight(scene, topology, false), probed = skyLight(scene, topology, true);
        int tops = 0;
        for (std::size_t i = 0; i < topology.size(); ++i) {
            const SurfacePatch &patch = topology.patches[i];
            if (!patch.isSurface() || patch.normal.z < 0.99) continue;  // the top only: the sides see snow beside
            ++tops;
            EXPECT_EQ(probed.skyOnSurface[i], traced.skyOnSurface[i]) << "roof " << roof << ", voxel " << i;
            EXPECT_EQ(probed.snowRays[i], traced.snowRays[i]) << "roof " << roof << ", voxel " << i;
            EXPECT_GT(traced.skyOnSurface[i].x, 0.0f);
        }
        EXPECT_GT(tops, 100) << "roof " << roof;
    }
}

}  // namespace firn
