// A surface patch's sky rays past its probes (SkyRays, computeIncidentLight): spared where the probes see open sky,
// without moving the patches' sky on average.
#include <gtest/gtest.h>

#include <cmath>

#include "firn/geometry/mesh.h"
#include "firn/transport/incident_light.h"
#include "firn/util/openvdb_library.h"
#include "firn/util/sampling.h"

namespace firn {
namespace {

constexpr int kSide = 40;           // voxels of 1 cm across the slab
constexpr double kPlateEdge = 0.2;  // m: the plate covers x below this, 3 voxels above the slab's top

// A slab 40 x 40 x 3 voxels (sigma_t h 10) under a uniform sky (pi L = pi W/m^2), a grey plate 3 voxels above its
// top over x < 20 voxels: the top patches near the plate's edge see it along some of their rays, the far ones none.
Scene slabUnderPlate() {
    initializeOpenVdb();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setTransform(openvdb::math::Transform::createLinearTransform(0.01));
    grid->fill(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(kSide - 1, kSide - 1, 2)), 100.0f);
    Scene scene;
    scene.medium = std::make_shared<Medium>(grid, VolumeOptics{10.0, Rgb(0.9), 0.6});
    scene.sky.radiance = Rgb(1.0);
    const float z = 0.06f, e = float(kPlateEdge), v[] = {-1, -1, z, e, -1, z, e, 2, z, -1, 2, z};
    const unsigned t[] = {0, 1, 2, 0, 2, 3};
    scene.occluders = std::make_shared<Occluders>(makeTriangleMesh(v, 4, t, 2), std::vector<Rgb>(2, Rgb(0.5)));
    return scene;
}

struct TopSky {
    double band = 0.0;  // W/m^2: skyOnSurface's mean (channel 0) over the top patches at x 14-29 voxels
    int openProbesRestMarked = 0;  // top patches whose probes met nothing and some other ray snow or the plate
};

TopSky topSky(const Scene &scene, const SnowTopology &topo, double restShare, std::uint64_t seed) {
    const IncidentLight light =
        computeIncidentLight(scene, topo, {9, 1, seed, false, restShare}, SubProgress(nullptr, 0.0, 1.0));
    const SkyRays rays(9, restShare);
    TopSky out;
    int count = 0;
    for (std::size_t i = 0; i < topo.size(); ++i) {
        const openvdb::Coord &c = topo.coord[i];
        if (!topo.patches[i].isSurface() || topo.patches[i].sharp || c.z() != 2 || c.y() < 4 || c.y() >= kSide - 4)
            continue;
        const std::uint64_t marked = light.snowRays[i] | light.occluderRays[i];
        out.openProbesRestMarked += !(marked & rays.probes()) && (marked & ~rays.probes());
        if (c.x() >= 14 && c.x() < 30) out.band += light.skyOnSurface[i].x, ++count;
    }
    out.band /= count;
    return out;
}

}  // namespace

// Every ray traced (restShare 1) against the rays past an open patch's probes traced one time in four, weighted
// four times: near the plate's edge some patches' probes miss the plate while other rays of theirs meet it; most of
// those patches spare the rays that would have, yet the band's sky keeps its mean over 16 seeds (unbiased).
TEST(SkyRays, AnOpenPatchSparesMostOfItsOtherRaysAndKeepsItsSkyOnAverage) {
    const Scene scene = slabUnderPlate();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    constexpr int kSeeds = 16;
    double all = 0.0, spared = 0.0, difference2 = 0.0;
    int markedAll = 0, markedSpared = 0;
    for (std::uint64_t seed = 0; seed < kSeeds; ++seed) {
        const TopSky a = topSky(scene, topo, 1.0, seed), b = topSky(scene, topo, 0.25, seed);
        all += a.band / kSeeds, spared += b.band / kSeeds;
        difference2 += (b.band - a.band) * (b.band - a.band) / kSeeds;
        markedAll += a.openProbesRestMarked, markedSpared += b.openProbesRestMarked;
    }
    // The same probes both ways (a ray's direction depends on the seed, the patch and its index only).
    EXPECT_GT(markedAll, 200);
    EXPECT_GT(markedSpared, 0);
    EXPECT_LT(markedSpared, markedAll / 2);  // about a quarter of them trace the rest
    // The band lies partly under the plate: its sky between the plate's shadow and the open sky's pi.
    EXPECT_GT(all, 0.5 * kPi);
    EXPECT_LT(all, 0.95 * kPi);
    // Unbiased: the seeds' mean difference within three standard errors of it (and within 1 %).
    const double standardError = std::sqrt(difference2 / kSeeds);
    EXPECT_LT(std::abs(spared - all), 3.0 * standardError + 1e-9);
    EXPECT_LT(std::abs(spared - all), 0.01 * all);
}

}  // namespace firn
