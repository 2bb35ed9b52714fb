// The bake against the independent Monte Carlo reference (monte_carlo.h: brute-force path tracing of the
// same medium, lights and occluders, sharing none of the bake's approximations) on a heterogeneous
// scene: a bumpy snow layer on a coloured ground, a plate above it casting a shadow; and a sky-lit ball.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "density_grid.h"
#include "firn/transport/bake.h"
#include "firn/transport/monte_carlo.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr double kVoxel = 0.01;     // m
constexpr float kDensity = 300.0f;  // kg/m^3

// Snow 6 cm deep with 3.5 cm bumps (slopes up to 40 degrees) on 40 x 40 cm, antialiased over one voxel
// at the top like the snow generator's, standing on a ground plane at z = 0 (its density reaches two
// voxels below, as metaballs' does).
openvdb::FloatGrid::Ptr bumpyLayer() {
    auto grid = test::densityGrid(kVoxel);
    auto access = grid->getAccessor();
    for (int i = -20; i < 20; ++i)
        for (int j = -20; j < 20; ++j) {
            const double x = i * kVoxel, y = j * kVoxel;
            const double top = 0.06 + 0.035 * std::sin(2.0 * kPi * x / 0.25) * std::cos(2.0 * kPi * y / 0.3);
            for (int k = -2; k * kVoxel < top + kVoxel; ++k) {
                const double filled = std::clamp((top - k * kVoxel) / kVoxel + 0.5, 0.0, 1.0);
                if (filled > 0.0) access.setValue(openvdb::Coord(i, j, k), float(kDensity * filled));
            }
        }
    return grid;
}

// A reddish ground quad at z = 0 and a grey plate 40 cm up whose shadow crosses the snow.
std::shared_ptr<const Occluders> groundAndPlate() {
    const float v[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0, 0.2f, -0.3f, 0.4f, 0.3f, -0.3f, 0.4f, 0.3f, 0.3f, 0.4f, 0.2f, 0.3f, 0.4f};
    const unsigned t[] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
    const Rgb ground(0.7, 0.35, 0.1), plate(0.2);
    return std::make_shared<Occluders>(makeTriangleMesh(v, 8, t, 4), std::vector<Rgb>{ground, ground, plate, plate});
}

struct Pixel {
    std::vector<Ray> rays;  // spread over the pixel's footprint (2 x 2.2 cm): pixels span several voxels
};

// An orthographic camera 30 degrees off vertical, looking at the snow towards the sun.
std::vector<Pixel> camera(int pixels, int sub) {
    const glm::dvec3 view = glm::normalize(glm::dvec3(0.3, 0.4, -0.85));
    const Frame frame(-view);
    const double size = 0.022 * 14.0 / pixels;
    std::vector<Pixel> out(pixels * pixels);
    for (int a = 0; a < pixels; ++a)
        for (int b = 0; b < pixels; ++b)
            for (int i = 0; i < sub; ++i)
                for (int j = 0; j < sub; ++j) {
                    const double u = (a - pixels / 2.0 + (i + 0.5) / sub) * size, v = (b - pixels / 2.0 + (j + 0.5) / sub) * size;
                    out[a * pixels + b].rays.push_back({frame.toWorld(u, v, 0.0) + glm::dvec3(0, 0, 0.05) - 0.6 * view, view});
                }
    return out;
}

struct Comparison {
    Rgb meanAbsoluteError{0.0}, meanStandardError{0.0};  // relative, per channel, over pixels
};

Comparison compare(const Scene &scene, int pixels, int sub, int samplesPerPixel, int sourceScale = 0) {
    BakeSettings settings;
    settings.sourceScale = sourceScale;
    const BakedGrids baked = bakeScattering(scene, settings);
    const std::vector<Pixel> image = camera(pixels, sub);
    std::vector<Ray> rays;
    for (const Pixel &pixel : image) rays.insert(rays.end(), pixel.rays.begin(), pixel.rays.end());
    const std::vector<RadianceEstimate> reference =
        MonteCarloReference(scene).estimate(rays, samplesPerPixel / (sub * sub), 2024);
    Comparison out;
    const double n = sub * sub;
    for (std::size_t p = 0; p < image.size(); ++p) {
        Rgb bake(0.0), mc(0.0), variance(0.0);
        for (std::size_t r = 0; r < image[p].rays.size(); ++r) {
            bake += renderBaked(scene, baked, image[p].rays[r]) / n;
            const RadianceEstimate &e = reference[p * image[p].rays.size() + r];
            mc += e.mean / n;
            variance += e.standardError * e.standardError / (n * n);
        }
        EXPECT_GT(mc.y, 0.05) << "pixel " << p << " should see lit snow";
        out.meanAbsoluteError += glm::abs(bake - mc) / mc / double(image.size());
        out.meanStandardError += glm::sqrt(variance) / mc / double(image.size());
    }
    return out;
}

// The bake is within `goal` of the truth on average: with Monte Carlo noise of relative standard error s
// per pixel, the measured mean |error| may exceed that by up to sqrt(2 / pi) s ~ 0.8 s.
void expectWithin(const Comparison &c, double goal) {
    std::printf("mean |relative error| (R G B): %.4f %.4f %.4f; reference's relative standard error %.4f %.4f %.4f\n",
                c.meanAbsoluteError.x, c.meanAbsoluteError.y, c.meanAbsoluteError.z, c.meanStandardError.x,
                c.meanStandardError.y, c.meanStandardError.z);
    for (int ch = 0; ch < 3; ++ch) {
        EXPECT_LT(c.meanStandardError[ch], 0.03) << "reference too noisy to judge, channel " << ch;
        EXPECT_LT(c.meanAbsoluteError[ch], goal + 0.8 * c.meanStandardError[ch]) << "channel " << ch;
    }
}

Scene bumpyScene(double g, Rgb omega = Rgb(0.999, 0.9995, 0.9998)) {
    Scene scene;
    scene.medium = std::make_shared<Medium>(bumpyLayer(), VolumeOptics{1000.0 / kDensity, omega, g});
    scene.occluders = groundAndPlate();
    return scene;
}

// `scene` under the tests' sun (its plate's shadow crossing the bumps) and a uniform sky of 0.15.
Scene underSunAndSky(Scene scene) {
    scene.sky.radiance = Rgb(0.15);
    scene.suns = {SunLight{glm::normalize(glm::dvec3(0.5, 0.3, 0.8)), Rgb(1.0), 0.0093}};
    return scene;
}

// A lamp 45 cm above the bumps, beside the plate (whose shadow it casts), with g 0.6 as for the sun.
Scene lampLitScene(Lamp::Shape shape) {
    Scene scene = bumpyScene(0.6);
    Lamp lamp;
    lamp.shape = shape;
    lamp.position = {-0.15, 0.1, 0.45};
    lamp.axis = glm::normalize(glm::dvec3(0.2, -0.1, -1.0));
    lamp.tangent = glm::normalize(glm::cross(lamp.axis, glm::dvec3(0.0, 1.0, 0.0)));
    lamp.emission = Rgb(0.25);  // W/sr: about 1 W/m^2 on the snow below
    lamp.radius = 0.02;
    lamp.spotAngle = 1.6, lamp.spotBlend = 0.3;  // the view lies inside the cone, its blend beyond
    if (lamp.isArea()) lamp.emission = Rgb(8.0), lamp.sizeX = 0.2, lamp.sizeY = 0.12;  // W/m^2/sr
    scene.lamps = {lamp};
    return scene;
}

}  // namespace

// Each lamp type lights the bumps as the reference says (issue goal: within 10 %).
TEST(BakeVersusMonteCarlo, PointLampLitBumpySnow) { expectWithin(compare(lampLitScene(Lamp::Shape::Point), 6, 2, 2048), 0.1); }
TEST(BakeVersusMonteCarlo, SpotLampLitBumpySnow) { expectWithin(compare(lampLitScene(Lamp::Shape::Spot), 6, 2, 2048), 0.1); }
TEST(BakeVersusMonteCarlo, RectangleLampLitBumpySnow) {
    expectWithin(compare(lampLitScene(Lamp::Shape::Rectangle), 6, 2, 2048), 0.1);
}
TEST(BakeVersusMonteCarlo, EllipseLampLitBumpySnow) {
    expectWithin(compare(lampLitScene(Lamp::Shape::Ellipse), 6, 2, 2048), 0.1);
}

// Snow's own optics (g 0.85) under a uniform sky: light between the bumps, the plate's shade, the
// ground's colour through the thin snow.
TEST(BakeVersusMonteCarlo, SkyLitBumpySnow) {
    Scene scene = bumpyScene(0.85);
    scene.sky.radiance = Rgb(0.15);
    expectWithin(compare(scene, 10, 2, 400), 0.05);
}

// Sun and sky with the plate's shadow crossing the bumps, seen against the sun. (g 0.6: with snow's
// 0.85 the reference's shadow rays are too noisy for a test of this size.)
TEST(BakeVersusMonteCarlo, SunLitBumpySnowWithShadow) {
    Scene scene = underSunAndSky(bumpyScene(0.6));
    expectWithin(compare(scene, 8, 2, 1024), 0.05);
}

// A mixed render (estimateMixed) that scatters in all the snow, bakes none of it and bounces without limit is the
// reference itself: one loop, the same paths from the same streams, to the bit.
TEST(MonteCarloReference, MixedRenderScatteringEverywhereIsTheReference) {
    Scene scene = underSunAndSky(bumpyScene(0.6));
    const MonteCarloReference reference(scene);
    std::vector<Ray> rays;
    for (const Pixel &pixel : camera(4, 1)) rays.push_back(pixel.rays[0]);
    const std::vector<RadianceEstimate> plain = reference.estimate(rays, 16, 7);
    const std::vector<RadianceEstimate> mixed = estimateMixed(reference, rays, 16, 7, [] {
        MixedRender scatterAll;
        scatterAll.emittedAlong = [](const Ray &, double) { return Rgb(0.0); };
        scatterAll.emittedAt = [](const glm::dvec3 &, const glm::dvec3 &) { return Rgb(0.0); };
        scatterAll.scatterShare = [](const glm::dvec3 &) { return 1.0; };
        return scatterAll;
    });
    for (std::size_t i = 0; i < rays.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(plain[i].mean[c], mixed[i].mean[c]) << "ray " << i << ", channel " << c;
            EXPECT_EQ(plain[i].standardError[c], mixed[i].standardError[c]) << "ray " << i << ", channel " << c;
        }
    EXPECT_GT(plain[5].mean.y, 0.0);  // the rays see lit snow
}

// Sooty snow, far from clean (omega 0.9, 0.95, 0.99: y = 0.9, 0.6, 0.3), under the same sun and sky: what
// returns of the sun after few scatterings keeps its direction (the absorbing sun lobe, sun_lobe.h). Measured:
// 13 %, 6 %, 5 % (the non-absorbing lobe gave 20 %, 7 %, 4 %); the goal of 5 % is not met at omega 0.9,
// where the diffusion's flux itself errs, so this guards the lobe at 15 %.
TEST(BakeVersusMonteCarlo, AbsorbingSnowUnderTheSun) {
    Scene scene = underSunAndSky(bumpyScene(0.6, Rgb(0.9, 0.95, 0.99)));
    expectWithin(compare(scene, 8, 2, 2048), 0.15);
}

// The same with the source grids 2x coarser than the density, as large scenes get them.
TEST(BakeVersusMonteCarlo, SunLitBumpySnowWithCoarseSource) {
    Scene scene = underSunAndSky(bumpyScene(0.6));
    expectWithin(compare(scene, 8, 2, 1024, 2), 0.05);
}

namespace {

// bench/bake_suite.py's balls: r `radius` voxels on 1 cm voxels, the surface antialiased over one voxel, the centre
// between voxel centres (index -0.5 per axis, the origin), 100 kg/m^3 inside. ball_issue's: r 5.
openvdb::FloatGrid::Ptr suiteBall(int radius) {
    auto grid = test::densityGrid(kVoxel);
    auto access = grid->getAccessor();
    for (int i = -radius - 3; i < radius + 3; ++i)
        for (int j = -radius - 3; j < radius + 3; ++j)
            for (int k = -radius - 3; k < radius + 3; ++k) {
                const double distance = glm::length(glm::dvec3(i + 0.5, j + 0.5, k + 0.5)) - radius;  // voxels
                const double filled = std::clamp(0.5 - distance, 0.0, 1.0);
                if (filled > 0.0) access.setValue(openvdb::Coord(i, j, k), float(100.0 * filled));
            }
    return grid;
}

// The light a ball at the origin sends towards a distant camera in direction `toCamera` (kPixels x kPixels parallel
// rays `spacing` m apart over the ball and its ramp), summed over the view (green), baked over the Monte Carlo
// reference's (`paths` per ray), and the reference's relative standard error.
struct ViewRatio {
    double ratio, noise;
};
ViewRatio viewRatio(const Scene &scene, const glm::dvec3 &toCamera, int kPixels, double spacing, int paths) {
    const BakedGrids baked = bakeScattering(scene, BakeSettings{});
    const glm::dvec3 right = glm::normalize(glm::cross(glm::dvec3(0.0, 0.0, 1.0), toCamera)),
                     up = glm::cross(toCamera, right);
    std::vector<Ray> rays;
    for (int a = 0; a < kPixels; ++a)
        for (int b = 0; b < kPixels; ++b)
            rays.push_back({0.3 * toCamera + (a - kPixels / 2 - 0.5) * spacing * right +
                                (b - kPixels / 2 - 0.5) * spacing * up,
                            -toCamera});
    const std::vector<RadianceEstimate> reference = MonteCarloReference(scene).estimate(rays, paths, 2024);
    double bake = 0.0, mc = 0.0, variance = 0.0;
    for (std::size_t r = 0; r < rays.size(); ++r) {
        bake += renderBaked(scene, baked, rays[r]).y;
        mc += reference[r].mean.y;
        variance += reference[r].standardError.y * reference[r].standardError.y;
    }
    return {bake / mc, std::sqrt(variance) / mc};
}

}  // namespace

// ball_issue's snow (sigma_t 1000/m, omega 0.98, g 0.85) under a uniform sky alone, seen whole from the side: the
// light it sends back, summed over the view, against the reference. The density ramp over a convex surface sees sky
// from below the surface's plane through the thin snow past the limb, which the surface's half-space model lacks
// (skyInRamp, bake_grid_values.cpp): without it the bake reads 0.9258 of the reference, with it 0.9362 (standard
// error 0.0008; bench/ball_sky_split.py's view (180 deg, 0 deg): -6.8 -> -5.7 %). The rest of the deficit is the
// fringe's (docs/bake.md, Accuracy).
TEST(BakeVersusMonteCarlo, SkyLitBallKeepsTheSkyItsRampSeesFromBelow) {
    Scene scene;
    scene.medium = std::make_shared<Medium>(suiteBall(5), VolumeOptics{1000.0 / 100.0, Rgb(0.98), 0.85});
    scene.sky.radiance = Rgb(0.05);
    const ViewRatio view = viewRatio(scene, glm::dvec3(-1.0, 0.0, 0.0), 26, 0.005, 1024);
    std::printf("sky-lit ball: baked / reference %.4f (reference's relative standard error %.4f)\n", view.ratio,
                view.noise);
    EXPECT_LT(view.noise, 0.001);
    EXPECT_GT(view.ratio, 0.932 - 2.0 * view.noise);
    EXPECT_LT(view.ratio, 1.02 + 2.0 * view.noise);
}

// The same ball under a sun 30 degrees up, seen against it (the suite's view (180 deg, 0 deg)): the light the skin
// carries past the limb lights the limb ring (limbCarriedInRamp, bake_grid_values.cpp; docs/benchmarks.md,
// limb-ramp): without it the bake reads 0.8197 of the reference, with it 0.8331 (the reference's relative standard
// error 0.0067, the same paths for both: the bound between them holds the change, not the noise). Before
// bumpy-sides 0.8457 and 0.8596: sharp voxels on the ball's dark side took the sun through the ball.
TEST(BakeVersusMonteCarlo, SunLitBallSeenAgainstTheSunKeepsTheLightItsSkinCarriesPastTheLimb) {
    Scene scene;
    scene.medium = std::make_shared<Medium>(suiteBall(5), VolumeOptics{1000.0 / 100.0, Rgb(0.98), 0.85});
    scene.suns.push_back({glm::dvec3(std::cos(kPi / 6.0), 0.0, std::sin(kPi / 6.0)), Rgb(1.0)});
    const ViewRatio view = viewRatio(scene, glm::dvec3(-1.0, 0.0, 0.0), 26, 0.005, 1024);
    std::printf("ball against the sun: baked / reference %.4f (reference's relative standard error %.4f)\n",
                view.ratio, view.noise);
    EXPECT_LT(view.noise, 0.01);
    EXPECT_GT(view.ratio, 0.827);
    EXPECT_LT(view.ratio, 1.0 + 2.0 * view.noise);
}

// A ball of 8 voxels' radius (ball_snow's size; sigma_t h 20, omega 0.99, g 0.85) seen from its sun, 30 degrees up:
// the lit cap. The patches' exitance is per m^2 of the sphere on the density's half level, and the carried sun shown
// in the ramp beyond it is spread as over a sphere d voxels larger, 1 / (1 + kappa d)^2, while the sun the skin
// intercepts beyond the patches' surface is given to them (skin_ring.h; docs/benchmarks.md, cap-sphere and cap-rgb):
// without both the bake read 1.0916 of the reference on these rays (the undivided light shown over the density's
// larger ball), with them 0.9801 (the reference's relative standard error 0.0109, the same paths for both).
TEST(BakeVersusMonteCarlo, SunLitBallSeenFromItsSunShowsTheCapsLightOverItsOwnSphere) {
    Scene scene;
    scene.medium = std::make_shared<Medium>(suiteBall(8), VolumeOptics{2000.0 / 100.0, Rgb(0.99), 0.85});
    const glm::dvec3 sun(std::cos(kPi / 6.0), 0.0, std::sin(kPi / 6.0));
    scene.suns.push_back({sun, Rgb(1.0)});
    const ViewRatio view = viewRatio(scene, sun, 16, 0.015, 1024);
    std::printf("ball from its sun: baked / reference %.4f (reference's relative standard error %.4f)\n", view.ratio,
                view.noise);
    EXPECT_LT(view.noise, 0.012);
    EXPECT_GT(view.ratio, 0.95 - 2.0 * view.noise);
    EXPECT_LT(view.ratio, 1.04 + 2.0 * view.noise);
}

}  // namespace firn
