// The bake against physics: the exact semi-infinite table (adding-doubling / Chandrasekhar H-functions,
// /work/shared/notes/snow-optics.md), energy conservation, and the independent Monte Carlo reference.
#include "firn/transport/bake.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>

#include "firn/transport/monte_carlo.h"
#include "firn/transport/slab.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"
#include "firn/util/threads.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.01;    // m
constexpr float kDensity = 300.0f;  // kg/m^3

Scene slabScene(double sigmaT, double omega, double g, int width, int layers) {
    Scene scene;
    scene.medium = std::make_shared<Medium>(makeSlabDensity(kVoxel, width, layers, kDensity),
                                            VolumeOptics{sigmaT / kDensity, Rgb(omega), g});
    return scene;
}

SunLight sunAt(double mu0) { return SunLight{{std::sqrt(1.0 - mu0 * mu0), 0.0, mu0}, Rgb(1.0), 0.0}; }

// Reflected flux over incident flux at the slab's centre, from the radiance Cycles would render.
double planeAlbedo(const Scene &scene, const BakedGrids &baked, double mu0) {
    return renderedExitance(scene, baked, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}, 0) / mu0;
}

// Exact plane albedo A(mu0) (notes' table).
struct ExactCase {
    double g, omega, sigmaT, A1, A05;
    int width, layers;
};
// Real snow: sigma_t of thousands per metre, 1 cm voxels, so each voxel is 20-50 optical depths thick.
const ExactCase kCases[] = {{0.0, 0.999, 2000.0, 0.91285, 0.93806, 40, 30}, {0.87, 0.9999, 5000.0, 0.92182, 0.94594, 32, 30}};

// A slab of snow, 32 x 32 x 8 voxels at sigma_t h 15, under a sun 40 degrees high and a grey sky, on a wider ground
// of this albedo.
Scene slabOnGround(double albedo) {
    Scene scene = slabScene(1500.0, 0.999, 0.7, 32, 8);
    scene.suns = {SunLight{glm::normalize(glm::dvec3(0.766, 0.0, 0.643)), Rgb(1.0), 0.0093}};
    scene.sky.radiance = Rgb(0.3);
    const float z = float(-8.25 * kVoxel);  // a quarter voxel under the slab's lowest voxel
    const float v[] = {-1, -1, z, 1, -1, z, 1, 1, z, -1, 1, z};
    const unsigned t[] = {0, 1, 2, 0, 2, 3};
    scene.occluders = std::make_shared<Occluders>(makeTriangleMesh(v, 4, t, 2), std::vector<Rgb>(2, Rgb(albedo)));
    return scene;
}

}  // namespace

// With source grids as fine as the density, and 2x coarser (what large scenes get).
TEST(Bake, SlabPlaneAlbedoMatchesExactValues) {
    for (int scale : {1, 2})
        for (const ExactCase &c : kCases)
            for (double mu0 : {1.0, 0.5}) {
                Scene scene = slabScene(c.sigmaT, c.omega, c.g, c.width, c.layers);
                scene.suns = {sunAt(mu0)};
                BakeSettings settings;
                settings.sourceScale = scale;
                const BakedGrids baked = bakeScattering(scene, settings);
                const double exact = mu0 == 1.0 ? c.A1 : c.A05, albedo = planeAlbedo(scene, baked, mu0);
                std::printf("source scale %d, g %.2f omega %.4f sun mu0 %.1f: bake %.4f exact %.5f (%+.2f %%)\n", scale,
                            c.g, c.omega, mu0, albedo, exact, 100.0 * (albedo / exact - 1.0));
                EXPECT_NEAR(albedo, exact, 0.01 * exact) << "g " << c.g << " mu0 " << mu0 << " scale " << scale;
            }
}

// By reciprocity A(mu) is also the radiance seen at cos(view) mu under a uniform sky of unit radiance.
TEST(Bake, SlabUnderUniformSkyShowsExactAlbedo) {
    for (const ExactCase &c : kCases) {
        Scene scene = slabScene(c.sigmaT, c.omega, c.g, c.width, c.layers);
        scene.sky.radiance = Rgb(1.0);
        const BakedGrids baked = bakeScattering(scene, BakeSettings{});
        for (double mu : {1.0, 0.5}) {
            const glm::dvec3 w(std::sqrt(1.0 - mu * mu), 0.0, mu);
            const double L = renderBaked(scene, baked, Ray{0.5 * w, -w})[0];
            const double exact = mu == 1.0 ? c.A1 : c.A05;
            std::printf("g %.2f omega %.4f sky view mu %.1f: bake %.4f exact %.5f (%+.2f %%)\n", c.g, c.omega, mu, L, exact,
                        100.0 * (L / exact - 1.0));
            EXPECT_NEAR(L, exact, 0.01 * exact) << "g " << c.g << " mu " << mu;
        }
    }
}

// Without absorption, reflected + transmitted (the uncollided beam included) = incident.
TEST(Bake, ConservativeSlabConservesEnergy) {
    const int layers = 6;
    Scene scene = slabScene(500.0, 1.0, 0.85, 48, layers);  // optical thickness 30, reduced 4.5
    const double mu0 = 0.8;
    scene.suns = {sunAt(mu0)};
    const BakedGrids baked = bakeScattering(scene, BakeSettings{});
    const double reflected = renderedExitance(scene, baked, {0, 0, 0}, {0, 0, 1}, 1);
    const double diffuse = renderedExitance(scene, baked, {0, 0, -layers * kVoxel}, {0, 0, -1}, 1);
    const double direct = mu0 * std::exp(-500.0 * layers * kVoxel / mu0);
    EXPECT_NEAR(reflected + diffuse + direct, mu0, 0.01 * mu0);
    EXPECT_GT(diffuse, 0.2 * mu0);  // a real transmission test, not a thick slab
}

// A convex edge over a black ground (a slab in the air, the sun straight above): the light beneath its edge voxel's
// top leaves within a diffusion length through the unlit side too, so the top's exit falls across that
// voxel towards the side (docs/benchmarks.md, plate-side and edge-corner). Rendered straight down across the edge
// voxel, relative to the inside, against the Monte Carlo on the same rays: with the edge voxel's top taken as the
// inside's own exit (before branch edge-corner) 0.79 where the truth is 0.69. Under a sky all round, which reaches
// the side as the top, both 1.05-1.09 and nothing moves.
TEST(Bake, ConvexEdgeShowsItsTopFallingTowardsTheSide) {
    const int width = 16, across = 8;
    // Straight down across the edge voxel's top (its outer face at x = -width h / 2), then onto the inside.
    std::vector<Ray> rays;
    for (int k = 0; k < across; ++k)
        rays.push_back({{(-0.5 * width + (k + 0.5) / across) * kVoxel, 0.5 * kVoxel, 5.0 * kVoxel}, {0.0, 0.0, -1.0}});
    rays.push_back({{0.0, 0.5 * kVoxel, 5.0 * kVoxel}, {0.0, 0.0, -1.0}});
    for (bool sun : {true, false}) {
        Scene scene = slabScene(1500.0, 0.999, 0.7, width, 6);  // sigma_t h 15: 4.5 transport mean free paths a voxel
        if (sun)
            scene.suns = {sunAt(1.0)};
        else
            scene.sky.radiance = Rgb(1.0);
        const BakedGrids baked = bakeScattering(scene, BakeSettings{});
        const std::vector<RadianceEstimate> truth = MonteCarloReference(scene).estimate(rays, 4096, 11);
        double expected = 0.0, rendered = 0.0;
        for (int k = 0; k < across; ++k) {
            expected += truth[std::size_t(k)].mean[0] / across;
            rendered += renderBaked(scene, baked, rays[std::size_t(k)])[0] / across;
        }
        expected /= truth.back().mean[0], rendered /= renderBaked(scene, baked, rays.back())[0];
        std::printf("%s: the edge voxel's top / the inside's: bake %.3f, Monte Carlo %.3f\n", sun ? "sun" : "sky",
                    rendered, expected);
        EXPECT_NEAR(rendered, expected, 0.06) << (sun ? "sun" : "sky");
    }
}

// A convex edge between a lit face and a shadowed one (a slab in the air, the sun from +x at 60 degrees from the
// zenith: its top lit, its -x side in shadow). The edge voxel's one lobe mixes its lit top with its dark side; the air
// across each of its flat faces carries that face's own exit (EdgeFaceLobes). Rendered head-on across each face of the
// edge voxel against the Monte Carlo on the same rays (4096 paths), relative to the inside's top: the top 0.711 with
// the voxel's one lobe in the air above it, 0.677 with the top's own, the truth 0.679. The side read 0.689 -> 0.741
// against 0.467, 0.734 with the faces relaxed no further than their mean (kappa 0.44 -> 0.40, branch edge-relax), 0.667
// with the air across it showing none of the top's sharply forward return (branch corner-fwd; docs/benchmarks.md,
// edge-faces, edge-relax, corner-fwd).
TEST(Bake, EdgeFacesBesideALitFaceShowTheirOwnExit) {
    const int width = 16, across = 8;
    Scene scene = slabScene(1500.0, 0.999, 0.7, width, 6);  // sigma_t h 15: 4.5 transport mean free paths a voxel
    scene.suns = {sunAt(0.5)};
    std::vector<Ray> rays;
    for (int k = 0; k < across; ++k)  // straight down onto the edge voxel's top
        rays.push_back({{(-0.5 * width + (k + 0.5) / across) * kVoxel, 0.5 * kVoxel, 5.0 * kVoxel}, {0.0, 0.0, -1.0}});
    for (int k = 0; k < across; ++k)  // head-on onto its side
        rays.push_back({{-(0.5 * width + 5.0) * kVoxel, 0.5 * kVoxel, -(k + 0.5) / across * kVoxel}, {1.0, 0.0, 0.0}});
    rays.push_back({{0.0, 0.5 * kVoxel, 5.0 * kVoxel}, {0.0, 0.0, -1.0}});
    const BakedGrids baked = bakeScattering(scene, BakeSettings{});
    const std::vector<RadianceEstimate> truth = MonteCarloReference(scene).estimate(rays, 4096, 11);
    for (int face = 0; face < 2; ++face) {
        double expected = 0.0, rendered = 0.0;
        for (int k = face * across; k < (face + 1) * across; ++k) {
            expected += truth[std::size_t(k)].mean[0] / across;
            rendered += renderBaked(scene, baked, rays[std::size_t(k)])[0] / across;
        }
        expected /= truth.back().mean[0], rendered /= renderBaked(scene, baked, rays.back())[0];
        std::printf("the edge voxel's %s / the inside's top: bake %.3f, Monte Carlo %.3f\n", face ? "side" : "top",
                    rendered, expected);
        if (face == 0) {
            EXPECT_NEAR(rendered, expected, 0.025);
        } else {
            // The shadowed side shows none of the lit top's sharply forward return (its SunPeak leaves through the
            // top: EdgeFaceLobes::peakShare, and the edge voxel shows it through the top's projected area alone,
            // peakSeenThroughFaces): 1.57 times the truth with it in the air across the side, 1.43 with it in the
            // edge voxel alone, 1.30 without; the rest of the excess is the side's one value per voxel where the
            // truth falls within two mean free paths of the edge (docs/benchmarks.md, corner-fwd, corner-lean).
            EXPECT_LT(rendered, 1.4 * expected);
        }
    }
}

TEST(Bake, OutputFollowsTheContract) {
    Scene scene = slabScene(2000.0, 0.999, 0.85, 12, 8);
    scene.sky.radiance = Rgb(1.0);
    for (int scale : {1, 2}) {
        BakeSettings settings{BakeQuality::Draft};
        settings.sourceScale = scale;
        const BakedGrids baked = bakeScattering(scene, settings);
        for (std::size_t k = 0; k < 4; ++k) {
            const auto &grid = baked.source[k];
            EXPECT_EQ(grid->getName(), BakedGrids::kNames[k]);
            EXPECT_EQ(grid->tree().activeTileCount(), 0u);
            // Source voxel I lies where density voxel scale * I does.
            for (const openvdb::Coord c : {openvdb::Coord(0), openvdb::Coord(3, -2, 5)})
                EXPECT_NEAR((grid->indexToWorld(c) - scene.medium->density().indexToWorld(c.asVec3d() * double(scale))).length(), 0.0, 1e-12);
            // Every active voxel on the outside of the grid is zero (Cycles misreads Vec3 grids' edges).
            openvdb::tree::ValueAccessor<const openvdb::Vec3fTree> acc(grid->tree());
            for (auto it = grid->cbeginValueOn(); it; ++it) {
                bool edge = false;
                for (int f = 0; f < 6 && !edge; ++f) edge = !acc.isValueOn(it.getCoord() + faceStep(f));
                if (edge) {
                    ASSERT_EQ(*it, openvdb::Vec3f(0.0f)) << grid->getName() << " at " << it.getCoord();
                }
            }
        }
        // Around the surface the ratio emission / extinction is constant: the source grid holds the same
        // value on the density's last voxel and two voxels (one coarse voxel) beyond it.
        openvdb::tree::ValueAccessor<const openvdb::Vec3fTree> l0(baked.source[0]->tree());
        const openvdb::Coord top(6 / scale, 6 / scale, -1);
        EXPECT_GT(l0.getValue(top).x(), 0.5f);
        for (int above = 1; above <= 2 / scale; ++above)
            EXPECT_NEAR(l0.getValue(top + openvdb::Coord(0, 0, above)).x(), l0.getValue(top).x(), 0.01f * l0.getValue(top).x());
    }
}

TEST(Bake, SameSeedSameResult) {
    Scene scene = slabScene(2000.0, 0.999, 0.85, 12, 8);
    scene.sky.radiance = Rgb(0.3);
    scene.suns = {SunLight{glm::normalize(glm::dvec3(0.3, 0.2, 1.0)), Rgb(1.0), 0.01}};
    const BakedGrids a = bakeScattering(scene, BakeSettings{BakeQuality::Draft, 5});
    const BakedGrids b = bakeScattering(scene, BakeSettings{BakeQuality::Draft, 5});
    for (std::size_t k = 0; k < 4; ++k) {
        openvdb::tree::ValueAccessor<const openvdb::Vec3fTree> other(b.source[k]->tree());
        for (auto it = a.source[k]->cbeginValueOn(); it; ++it) ASSERT_EQ(*it, other.getValue(it.getCoord()));
    }
}

// The occluders' send-back alone pays the gathering passes only where it brings much (kSendBackWorthPasses,
// IncidentLight::occluderShare 0.15): a slab of snow, 32 x 32 x 8 voxels at sigma_t h 15, on a wider ground whose
// albedo is all that differs. Its sides send half their sky rays to the ground and nothing hides any patch's sky,
// so the ground's albedo times their share decides: on a grey one (0.5: share 0.12) one solve, on a white one
// (0.97: 0.23) the passes (docs/bake.md Method 6; docs/benchmarks.md "send-back2", "hat-debts").
TEST(Bake, OnlyABrightGroundSendsEnoughBackForTheGatheringPasses) {
    const auto passesOver = [](double albedo) {
        BakeStats stats;
        bakeScattering(slabOnGround(albedo), BakeSettings{BakeQuality::Draft}, nullptr, &stats);
        return stats.passes;
    };
    EXPECT_EQ(passesOver(0.5), 1);
    EXPECT_GT(passesOver(0.97), 1);
}

// Passes before the last only feed the gathering (a few per cent of the last pass's sources), so their solves stop
// at bake.cpp's kGatheredPassTolerance (1e-1) and the last at the quality's (Draft: 1e-4): the slab on a white
// ground, which takes the gathering passes.
TEST(Bake, SolvesThePassesBeforeTheLastLooser) {
    BakeStats stats;
    bakeScattering(slabOnGround(0.97), BakeSettings{BakeQuality::Draft}, nullptr, &stats);
    ASSERT_GT(stats.passes, 1);
    ASSERT_EQ(stats.relativeResidual.size(), std::size_t(stats.passes));
    ASSERT_EQ(stats.iterations.size(), std::size_t(stats.passes));
    for (int c = 0; c < 3; ++c) {
        EXPECT_LE(stats.relativeResidual.front()[c], 1e-1);
        EXPECT_LE(stats.relativeResidual.back()[c], 1e-4);
    }
    const auto &first = stats.relativeResidual.front();
    EXPECT_GT(*std::max_element(first.begin(), first.end()), 1e-4);  // looser than the last
}

// FINAL's last solve stops at its quality's tolerance (1e-4), not at convergence: what that leaves in the grids must
// lie far under what the bake's own sampling leaves (another seed). The slab on a white ground (two passes), its
// broad lobe's l0 against the same bake with its last solve taken to 1e-10, and against another seed, as
// sum |a - b| / sum |a|.
TEST(Bake, FinalSolveErrorLiesFarUnderTheBakesNoise) {
    const Scene scene = slabOnGround(0.97);
    const auto l0 = [&](std::uint64_t seed, double tolerance) {
        BakeSettings settings{BakeQuality::Final, seed};
        settings.tolerance = tolerance;
        return bakeScattering(scene, settings).source[0];
    };
    const auto difference = [](const openvdb::Vec3fGrid &a, const openvdb::Vec3fGrid &b) {
        openvdb::tree::ValueAccessor<const openvdb::Vec3fTree> other(b.tree());
        double apart = 0.0, total = 0.0;
        for (auto it = a.cbeginValueOn(); it; ++it)
            for (int c = 0; c < 3; ++c) {
                apart += std::abs(double((*it)[c]) - double(other.getValue(it.getCoord())[c]));
                total += std::abs(double((*it)[c]));
            }
        return apart / total;
    };
    const auto atFinal = l0(0, 0.0), converged = l0(0, 1e-10), otherSeed = l0(1, 0.0);
    const double solve = difference(*converged, *atFinal), noise = difference(*atFinal, *otherSeed);
    EXPECT_GT(noise, 0.0);
    EXPECT_LT(solve, 0.01 * noise) << "solve " << solve << ", noise " << noise;
}

TEST(Bake, ReportsProgressAndStopsWhenCancelled) {
    Scene scene = slabScene(2000.0, 0.999, 0.85, 16, 8);
    scene.sky.radiance = Rgb(1.0);
    double last = -1.0;
    bool monotone = true;
    Progress progress([&](double fraction, const std::string &) {
        monotone = monotone && fraction >= last;
        last = fraction;
    });
    bakeScattering(scene, BakeSettings{BakeQuality::Draft}, &progress);
    EXPECT_DOUBLE_EQ(progress.fraction(), 1.0);
    EXPECT_TRUE(monotone);
    Progress cancelled;
    cancelled.cancel();
    EXPECT_THROW(bakeScattering(scene, BakeSettings{}, &cancelled), Cancelled);
}

// Thin snow is traced beside the sun and sky light (bakeScattering): a small lump above the slab, traced whole. Its
// grids do not depend on how the two share the threads (one thread runs them one after the other, two side by
// side), the progress moves while they run and only goes forwards, and a bake cancelled as they start stops in
// them.
TEST(Bake, SnowTracedBesideTheLightIsTheSameOnOneThreadAndStopsWhenCancelled) {
    Scene scene = slabScene(2000.0, 0.999, 0.85, 12, 6);
    openvdb::FloatGrid::Ptr density = makeSlabDensity(kVoxel, 12, 6, kDensity);
    for (int x = 0; x < 2; ++x)
        for (int y = 0; y < 2; ++y) density->tree().setValue(openvdb::Coord(x, y, 4), 0.05f * kDensity);  // 4 voxels above, tau 1
    scene.medium = std::make_shared<Medium>(density, scene.medium->optics());
    scene.sky.radiance = Rgb(0.5);
    scene.suns = {sunAt(0.7)};
    const BakeSettings settings{BakeQuality::Draft, 3};
    BakeStats stats;
    const BakedGrids both = bakeScattering(scene, settings, nullptr, &stats);
    EXPECT_EQ(stats.tracedVoxels, 4u);
    setThreadCount(1);
    const BakedGrids one = runInCoreArena([&] { return bakeScattering(scene, settings); });
    setThreadCount(0);
    for (std::size_t k = 0; k < BakedGrids::kCount; ++k) {
        ASSERT_EQ(both.source[k]->activeVoxelCount(), one.source[k]->activeVoxelCount());
        openvdb::tree::ValueAccessor<const openvdb::Vec3fTree> other(one.source[k]->tree());
        for (auto it = both.source[k]->cbeginValueOn(); it; ++it) ASSERT_EQ(*it, other.getValue(it.getCoord()));
    }
    // Every report called back (interval 0): fractions within the two's stage, between its start and end.
    std::vector<std::pair<double, std::string>> seen;
    Progress progress([&](double f, const std::string &stage) { seen.emplace_back(f, stage); }, 0.0);
    bakeScattering(scene, settings, &progress);
    for (std::size_t i = 1; i < seen.size(); ++i) ASSERT_GE(seen[i].first, seen[i - 1].first) << seen[i].second;
    EXPECT_TRUE(std::any_of(seen.begin(), seen.end(), [](const auto &s) {
        return s.second == kLightAndTraceStage && s.first > 0.05 && s.first < 0.4;
    }));
    // Cancelled when the callback first sees their stage (a new stage is always called back): the bake stops
    // within the two, before any later stage.
    std::vector<std::string> stages;
    Progress cancelled([&](double, const std::string &stage) {
        stages.push_back(stage);
        if (stage == kLightAndTraceStage) cancelled.cancel();
    });
    EXPECT_THROW(bakeScattering(scene, settings, &cancelled), Cancelled);
    ASSERT_FALSE(stages.empty());
    EXPECT_EQ(stages.back(), kLightAndTraceStage);
}

TEST(Bake, RejectsBadInput) {
    Scene scene = slabScene(2000.0, 0.999, 0.85, 4, 4);
    scene.suns = {SunLight{{0.0, 0.0, 2.0}, Rgb(1.0), 0.0}};  // not a unit vector
    EXPECT_THROW(bakeScattering(scene, BakeSettings{}), InvalidArgument);
    BakeSettings settings;
    settings.skySamples = -1;
    scene.suns.clear();
    EXPECT_THROW(bakeScattering(scene, settings), InvalidArgument);
    EXPECT_THROW(Medium(makeSlabDensity(kVoxel, 4, 4, kDensity), VolumeOptics{0.0, Rgb(0.9), 0.8}), InvalidArgument);
    EXPECT_THROW(Medium(makeSlabDensity(kVoxel, 4, 4, kDensity), VolumeOptics{1.0, Rgb(1.1), 0.8}), InvalidArgument);
}

// Fuzzing (issue 11): sun_samples=10**9 baked on for hours; absurd counts are refused at once.
TEST(Bake, HugeSampleCountsAreRefused) {
    Scene scene = slabScene(2000.0, 0.999, 0.85, 4, 4);
    scene.suns = {sunAt(0.5)};
    BakeSettings settings;
    settings.quality = BakeQuality::Draft;
    settings.sunSamples = 1000000000;
    EXPECT_THROW(bakeScattering(scene, settings), InvalidArgument);
    settings.sunSamples = 0;
    settings.referenceSamples = 1000000000;
    settings.quality = BakeQuality::Reference;
    EXPECT_THROW(bakeScattering(scene, settings), InvalidArgument);
}

// Fuzzing (issue 11): 1e30 m^2/kg, or 1 m voxels of dense snow, broke the solver with a raw std::runtime_error.
TEST(Bake, OpticallyAbsurdVoxelsAreInvalidArguments) {
    EXPECT_THROW(Medium(makeSlabDensity(kVoxel, 2, 2, kDensity), VolumeOptics{1e30, Rgb(0.9), 0.5}), InvalidArgument);
    EXPECT_THROW(Medium(makeSlabDensity(kVoxel, 2, 2, 1e6f), VolumeOptics{1.0, Rgb(0.9), 0.5}), InvalidArgument);
    Scene scene;
    scene.medium = std::make_shared<Medium>(makeSlabDensity(1.0, 3, 3, 586.0f), VolumeOptics{8.6, Rgb(0.93), 0.39});
    scene.sky.radiance = Rgb(1.0);
    BakeSettings settings;
    settings.quality = BakeQuality::Draft;
    EXPECT_THROW(bakeScattering(scene, settings), InvalidArgument);
}

// Fuzzing (issue 11): write_slab_vdb(width=100000) filled 1e10 voxels until memory ran out.
TEST(Bake, TestSlabIsRefusedOverItsBudget) {
    EXPECT_THROW(makeSlabDensity(kVoxel, 100000, 100000, kDensity), BudgetExceeded);
    EXPECT_THROW(makeSlabDensity(INFINITY, 4, 4, kDensity), InvalidArgument);
}

}  // namespace firn
