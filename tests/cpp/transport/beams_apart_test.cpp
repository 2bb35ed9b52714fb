// The diffusion's sources and solution with the beams (suns, lamps) kept apart from the sky (assemble's beamsApart,
// bake.cpp's solveBeamsApart): the assembly is linear in the light, so the beams' part of one scene's sources is the
// whole sources of the same scene under its suns alone, and the rest those under its sky alone.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include <gtest/gtest.h>

#include "box_scene.h"
#include "firn/transport/bake.h"
#include "firn/transport/bake_diffusion_system.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/multigrid.h"
#include "firn/transport/skin_ring.h"
#include "firn/transport/snow_topology.h"

namespace firn {

namespace {

// A 12-voxel box of absorbing snow (sigma_t h 20) under a sun of 4 W/m^2 60 degrees up and, where `sky`, a sky of
// unit radiance (pi W/m^2 on the top).
Scene litBox(bool sun, bool sky) {
    Scene scene = test::boxScene(openvdb::CoordBBox({0, 0, 0}, {11, 11, 11}), 300.0f,
                                 VolumeOptics{2000.0 / 300.0, Rgb(0.999), 0.87}, {0.4, 0.3, 0.87});
    scene.suns[0].irradiance = Rgb(4.0);
    if (!sun) scene.suns.clear();
    if (sky) scene.sky.radiance = Rgb(1.0);
    return scene;
}

// The green channel's system of `scene`, with its beams' part of the sources in `beams`.
struct Apart {
    bake::ChannelSystem system;
    UnwrittenVector<double> beams;
};
Apart greenSystem(const Scene &scene, const SnowTopology &topo) {
    const SubProgress none(nullptr, 0.0, 1.0);
    const IncidentLight light = computeIncidentLight(scene, topo, {16, 4, 7, false}, none);
    UnwrittenVector<double> beams(topo.size(), -1.0);
    bake::ChannelSystem system = bake::assemble(scene, topo, light, bake::skinRingGrowths(scene, topo, none), 1, none, bake::ChannelStorage{}, &beams);
    return {std::move(system), std::move(beams)};
}

double largest(const UnwrittenVector<double> &v) {
    double m = 0.0;
    for (const double x : v) m = std::max(m, std::abs(x));
    return m;
}

}  // namespace

TEST(BeamsApart, TheBeamsSourcesAreTheSunsAloneAndTheRestTheSkysAlone) {
    const Scene both = litBox(true, true), sun = litBox(true, false), sky = litBox(false, true);
    const SnowTopology topo = buildSnowTopology(*both.medium, *both.occluders, SubProgress(nullptr, 0.0, 1.0));
    const Apart whole = greenSystem(both, topo), sunAlone = greenSystem(sun, topo), skyAlone = greenSystem(sky, topo);
    const double scale = largest(whole.system.b);
    ASSERT_GT(scale, 0.0);
    double beams = 0.0, rest = 0.0;  // W
    for (std::size_t i = 0; i < topo.size(); ++i) {
        // The same sums in another order: rounding alone.
        EXPECT_NEAR(whole.beams[i], sunAlone.system.b[i], 1e-12 * scale) << i;
        EXPECT_NEAR(whole.system.b[i] - whole.beams[i], skyAlone.system.b[i], 1e-12 * scale) << i;
        EXPECT_EQ(sunAlone.beams[i], sunAlone.system.b[i]) << i;  // with no sky the sky part is zero
        EXPECT_EQ(skyAlone.beams[i], 0.0) << i;                   // with no beams theirs is
        beams += whole.beams[i], rest += whole.system.b[i] - whole.beams[i];
    }
    // Both parts hold a real share: the test is not of one part alone.
    EXPECT_GT(beams, 0.1 * (beams + rest));
    EXPECT_GT(rest, 0.1 * (beams + rest));
}

// The solve is linear: the beams' solution and the sky's add up to the single solve of both.
TEST(BeamsApart, TheTwoSolutionsAddUpToTheSingleSolve) {
    const Scene both = litBox(true, true);
    const SnowTopology topo = buildSnowTopology(*both.medium, *both.occluders, SubProgress(nullptr, 0.0, 1.0));
    Apart apart = greenSystem(both, topo);
    bake::ChannelSystem &system = apart.system;
    const SubProgress none(nullptr, 0.0, 1.0);
    UnwrittenVector<double> beams = apart.beams, sky(system.b);
    for (std::size_t i = 0; i < sky.size(); ++i) sky[i] -= beams[i];
    const MultigridSolver solver(std::move(system.A), std::move(system.remainder));
    UnwrittenVector<double> phi(topo.size(), 0.0), phiBeams(phi), phiSky(phi);
    solver.solve(system.b, phi, 1e-10, 500, none);
    solver.solve(beams, phiBeams, 1e-10, 500, none);
    solver.solve(sky, phiSky, 1e-10, 500, none);
    const double scale = largest(phi);
    ASSERT_GT(scale, 0.0);
    for (std::size_t i = 0; i < phi.size(); ++i) EXPECT_NEAR(phiBeams[i] + phiSky[i], phi[i], 1e-7 * scale) << i;
    EXPECT_GT(largest(phiBeams), 0.1 * scale);
    EXPECT_GT(largest(phiSky), 0.1 * scale);
}

// The bake solves the beams apart only where both lights shine: under a sun alone its start (the whole solution) is
// the beams' (no iteration), under a sky alone there are no beams (no solve).
TEST(BeamsApart, TheBakeIteratesOnTheBeamsOnlyUnderBothLights) {
    const auto beamIterations = [](const Scene &scene) {
        BakeStats stats;
        bakeScattering(scene, BakeSettings{}, nullptr, &stats);
        return stats.beamIterations;
    };
    EXPECT_EQ(beamIterations(litBox(true, false)), 0);
    EXPECT_EQ(beamIterations(litBox(false, true)), 0);
    EXPECT_GT(beamIterations(litBox(true, true)), 0);
}

}  // namespace firn
