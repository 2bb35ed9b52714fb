// Light tracing (light_tracing.h) against the per-voxel brute force it stands in for (MonteCarloReference::sourceIn),
// and its determinism across thread counts.
#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "density_grid.h"
#include "firn/transport/light_tracing.h"
#include "firn/util/random.h"
#include "test_geometry.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.01;  // m

// A cloud of lumps: half the voxels of a 10 cm cube filled at random (seeded), one optical depth each: about 500
// voxels touching through faces, edges or corners, more than a small piece (343); its lowest voxels' centres
// `bottom` voxels above z = 0 (the medium's bounds one voxel lower).
openvdb::FloatGrid::Ptr cloud(int bottom = 2) {
    auto grid = test::densityGrid(kVoxel);
    auto access = grid->getAccessor();
    Rng rng(7, 0);
    for (int i = 0; i < 1000; ++i)
        if (rng.uniform() < 0.5) access.setValue(openvdb::Coord(i % 10, i / 10 % 10, i / 100 + bottom), 10.0f);
    return grid;
}

// Sun and sky over a grey ground at z = 0, 2 cm under the cloud; sigma_t = 100 / m where there is snow, g 0.85.
Scene cloudScene(int bottom = 2, double groundAlbedo = 0.6) {
    Scene scene;
    scene.medium = std::make_shared<Medium>(cloud(bottom), VolumeOptics{10.0, Rgb(0.999, 0.99, 0.9), 0.85});
    const float v[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const unsigned t[] = {0, 1, 2, 0, 2, 3};
    scene.occluders = std::make_shared<Occluders>(makeTriangleMesh(v, 4, t, 2), std::vector<Rgb>(2, Rgb(groundAlbedo)));
    scene.suns = {SunLight{glm::normalize(glm::dvec3(0.5, 0.3, 0.8)), Rgb(1.0), 0.0093}};
    scene.sky.radiance = Rgb(0.1);
    return scene;
}

// The cloud 2 cm over a closed box of the snow's albedo whose top, at `top` (m), cuts its lowest voxels (lumps
// resting on the snow's surface mesh, closed and wound outwards); the medium's bounds and the light tracing's box
// reach below that top, so photons could start inside the box.
Scene cloudOverAClosedBox(double top) {
    Scene scene = cloudScene();
    const TriangleMesh box = test::box({-1.0f, -1.0f, -0.5f}, {1.0f, 1.0f, float(top)});
    scene.occluders = std::make_shared<Occluders>(box, std::vector<Rgb>(box.triangleCount(), Rgb(0.97)));
    return scene;
}

// The cloud with a ski in it: a closed box 3.7 mm thick (z = 0.0505 .. 0.0542) across the whole cloud, inside the
// voxels of its layer z = 5 (0.045 .. 0.055), between the planes 0.05 and 0.0545 of that layer's centres and of
// points 0.45 voxel towards their corners.
Scene cloudAroundASki() {
    Scene scene = cloudScene();
    const TriangleMesh ski = test::box({-0.02f, -0.02f, 0.0505f}, {0.12f, 0.12f, 0.0542f});
    scene.occluders = std::make_shared<Occluders>(ski, std::vector<Rgb>(ski.triangleCount(), Rgb(0.5)));
    return scene;
}

std::vector<openvdb::Coord> voxelsOf(const Scene &scene) {
    std::vector<openvdb::Coord> voxels;
    for (auto it = scene.medium->density().cbeginValueOn(); it; ++it) voxels.push_back(it.getCoord());
    return voxels;
}

double grey(const Rgb &c) { return (c.x + c.y + c.z) / 3.0; }

struct LayerLight {
    double traced, gathered;  // scattered l0 (all but the beams' single scattering), summed
};

// The scattered light of every other voxel of the cloud's layer z = `layer`: light traced (800,000 photons) and
// gathered per voxel (sourceIn, 1024 points each).
LayerLight layerLight(const Scene &scene, int layer) {
    const MonteCarloReference reference(scene);
    const std::vector<openvdb::Coord> voxels = voxelsOf(scene);
    const std::vector<SourceEstimate> traced =
        lightTracedSources(reference, voxels, LightTracingPlan{800'000, 16}, 3, SubProgress(nullptr, 0, 1));
    LayerLight out{0.0, 0.0};
    for (std::size_t v = 0; v < voxels.size(); v += 2) {
        if (voxels[v].z() != layer) continue;
        const SourceEstimate gathered = reference.sourceIn(voxels[v], 1024, 11, v);
        out.traced += grey(traced[v].l0 - traced[v].beamL0), out.gathered += grey(gathered.l0 - gathered.beamL0);
    }
    return out;
}

}  // namespace

// Each voxel's scattered light (all but the beams' single scattering, which both take from sourceIn's beams) as
// the per-voxel brute force gathers it. Oracle: sourceIn with 8192 points per voxel; the six voxels differed by
// -7.5 to +8.3 % (RMS 5 %: both estimates' noise; summed over half the cloud's voxels, with 256 points each and
// 10^6 photons, +0.2 % under the sky alone, +2.5 % under the sun alone): the bound is some 3 standard errors.
TEST(LightTracing, MatchesPerVoxelGathering) {
    const Scene scene = cloudScene();
    const MonteCarloReference reference(scene);
    std::vector<openvdb::Coord> voxels;
    for (auto it = scene.medium->density().cbeginValueOn(); it; ++it) voxels.push_back(it.getCoord());
    ASSERT_GT(voxels.size(), 343u);
    const LightTracingPlan plan{400'000, 64};
    const std::vector<SourceEstimate> traced = lightTracedSources(reference, voxels, plan, 3, SubProgress(nullptr, 0, 1));
    ASSERT_EQ(traced.size(), voxels.size());
    for (std::size_t v = 0; v < voxels.size(); v += voxels.size() / 5) {
        const SourceEstimate gathered = reference.sourceIn(voxels[v], 8192, 11, v);
        const double expected = grey(gathered.l0 - gathered.beamL0), got = grey(traced[v].l0 - traced[v].beamL0);
        std::printf("voxel (%d %d %d): scattered l0 %.5f traced, %.5f gathered; beams %.5f, %.5f\n", voxels[v].x(),
                    voxels[v].y(), voxels[v].z(), got, expected, grey(traced[v].beamL0), grey(gathered.beamL0));
        EXPECT_NEAR(got, expected, 0.15 * expected) << "voxel " << v;
    }
}

// The ground on the medium's bounds (the cloud's lowest voxels one voxel above it, as lumps over a snow surface
// meshed on the voxels' lattice), white as snow: photons reflecting off it inside the box and the light arriving
// through the box's bottom face (which holds its reflection) counted it twice: the two lowest layers' scattered
// light read +7 to +11 % (3 seeds; the whole cloud +4 %) before the box was set inside the bounds. Oracle: sourceIn
// with 1024 points on every other voxel of those layers; after, 6 seeds of both read -1 to +3 %: the bound holds
// both estimates' noise.
TEST(LightTracing, MatchesGatheringOverAGroundOnItsBounds) {
    const Scene scene = cloudScene(1, 0.97);
    const MonteCarloReference reference(scene);
    std::vector<openvdb::Coord> voxels;
    for (auto it = scene.medium->density().cbeginValueOn(); it; ++it) voxels.push_back(it.getCoord());
    ASSERT_NEAR(scene.medium->boundsMin().z, 0.0, 1e-12);
    const std::vector<SourceEstimate> traced =
        lightTracedSources(reference, voxels, LightTracingPlan{800'000, 16}, 3, SubProgress(nullptr, 0, 1));
    double got = 0.0, expected = 0.0;
    for (std::size_t v = 0; v < voxels.size(); v += 2) {
        if (voxels[v].z() > 2) continue;
        const SourceEstimate gathered = reference.sourceIn(voxels[v], 1024, 11, v);
        got += grey(traced[v].l0 - traced[v].beamL0), expected += grey(gathered.l0 - gathered.beamL0);
    }
    std::printf("lowest layers' scattered l0: %.5f traced, %.5f gathered\n", got, expected);
    EXPECT_NEAR(got, expected, 0.04 * expected);
}

// Lumps resting on a closed occluder (the snow's surface mesh): no light reaches its inside and no camera sees it, so
// a voxel's source is that of its part outside, as the per-voxel gathering takes it (sourceIn skips points inside:
// PathTracer::enclosed). Photons never collide inside, so their sums are over the part outside only: divided by the
// whole voxel's integral of sigma_t (before) the lowest layer read 0.39 of the gathering's light, by the midpoint rule
// on 4^3 points for the share outside 1.49 of it (the box's top near a row of points); jittered 8^3 (outsideShare)
// -1.6 % (4.88220 traced against 4.96175 gathered), and with the top at 0.0165 and under the layer (0.012) +1.5 %, -2.3 %;
// the cut cubes split by the top's plane (branch occluder-share) -2.0 % (4.85987). Oracle: sourceIn with 1024 points
// on every other voxel of that layer; the bound holds both estimates' noise.
TEST(LightTracing, CountsALumpsLightOverItsPartOutsideAClosedOccluder) {
    const Scene scene = cloudOverAClosedBox(0.0213);  // the lowest layer's voxels span z = 0.015 .. 0.025
    ASSERT_LT(scene.medium->boundsMin().z, 0.0213);
    const LayerLight light = layerLight(scene, 2);
    std::printf("lowest layer's scattered l0: %.5f traced, %.5f gathered\n", light.traced, light.gathered);
    EXPECT_NEAR(light.traced, light.gathered, 0.06 * light.gathered);
}

// A closed occluder thinner than a voxel inside the lumps (a ski in a spray): the voxels it cuts hold their light over
// their part outside it (0.63 of each), as the gathering takes it. outsideShare's 9 probes per voxel (before branch
// occluder-share) missed the ski between their planes and divided by the whole voxels' sigma_t: the ski's layer read
// 0.64 of the gathering's light (1.24653 traced, 1.95226 gathered); the exact test of the voxel's cube against the
// closed triangles +2.2 % (1.99586). Oracle: sourceIn with 1024 points on every other voxel of that layer; the bound
// holds both estimates' noise.
TEST(LightTracing, CountsTheLightOfLumpsAroundAThinClosedOccluder) {
    const LayerLight light = layerLight(cloudAroundASki(), 5);
    std::printf("the ski's layer's scattered l0: %.5f traced, %.5f gathered\n", light.traced, light.gathered);
    EXPECT_NEAR(light.traced, light.gathered, 0.06 * light.gathered);
}

// Light tracing is planned where the scene has occluders too (until branch spray-trace their voxels were left to the
// diffusion: bench/spray_light_bench.py's lumps over the snow's surface mesh 34 % per block off, bias +26 %).
TEST(LightTracing, IsPlannedWithOccluders) {
    const Scene scene = cloudOverAClosedBox(0.0213);
    const MonteCarloReference reference(scene);
    const LightTracingPlan plan = planLightTracing(reference, voxelsOf(scene), 2e8, 3);
    EXPECT_GT(plan.photons, 65536);
    EXPECT_GT(plan.beamSamples, 0);
}

namespace {

// Photon i from its own stream, sums reduced in chunk order: the same estimates on one thread and two.
void expectSameOnOneAndTwoThreads(const Scene &scene) {
    const MonteCarloReference reference(scene);
    const std::vector<openvdb::Coord> voxels = voxelsOf(scene);
    const LightTracingPlan plan{40'000, 4};
    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        return lightTracedSources(reference, voxels, plan, 5, SubProgress(nullptr, 0, 1));
    };
    const std::vector<SourceEstimate> one = run(1), two = run(2);
    for (std::size_t v = 0; v < voxels.size(); ++v) {
        EXPECT_EQ(one[v].l0, two[v].l0) << "voxel " << v;
        EXPECT_EQ(one[v].l1, two[v].l1) << "voxel " << v;
        EXPECT_EQ(one[v].third[2], two[v].third[2]) << "voxel " << v;
    }
}

}  // namespace

TEST(LightTracing, SameOnOneAndTwoThreads) { expectSameOnOneAndTwoThreads(cloudScene()); }

// With a closed occluder too: the emitter's photons of none inside it and the share outside of the voxels it cuts
// (outsideShare's jittered points, each voxel from its own stream).
TEST(LightTracing, SameOnOneAndTwoThreadsOverAClosedBox) { expectSameOnOneAndTwoThreads(cloudOverAClosedBox(0.0213)); }

// Around a ski too: the planes' columns and the edges' smallest cubes' points (outsideShare), each voxel's own stream.
TEST(LightTracing, SameOnOneAndTwoThreadsAroundASki) { expectSameOnOneAndTwoThreads(cloudAroundASki()); }

}  // namespace firn
