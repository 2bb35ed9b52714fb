#include "firn/transport/lights.h"

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/transport/lamps.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

// Blender's Environment Texture (equirectangular, default mapping): u = 0.5 looks along +X, u = 0.25
// along +Y, v = 1 is the zenith (Cycles' direction_to_equirectangular).
TEST(EnvironmentMap, FollowsBlendersEquirectangularConvention) {
    auto uv = EnvironmentMap::uvFromDirection({1, 0, 0});
    EXPECT_NEAR(uv.x, 0.5, 1e-12);
    EXPECT_NEAR(uv.y, 0.5, 1e-12);
    uv = EnvironmentMap::uvFromDirection({0, 1, 0});
    EXPECT_NEAR(uv.x, 0.25, 1e-12);
    EXPECT_NEAR(EnvironmentMap::uvFromDirection({0, 0, 1}).y, 1.0, 1e-12);
    EXPECT_NEAR(EnvironmentMap::uvFromDirection({0, 0, -1}).y, 0.0, 1e-12);
    for (const glm::dvec3 d : {glm::dvec3(0.3, -0.4, 0.5), glm::dvec3(-1, 0.2, -0.1)}) {
        const auto p = EnvironmentMap::uvFromDirection(d);
        const glm::dvec3 back = EnvironmentMap::directionFromUv(p.x, p.y);
        EXPECT_NEAR(glm::length(back - glm::normalize(d)), 0.0, 1e-12);
    }
}

TEST(EnvironmentMap, RowsRunFromNadirToZenith) {
    // 4 x 2 pixels: bottom row dark, top row bright.
    std::vector<Rgb> pixels(8, Rgb(0.0));
    for (int i = 4; i < 8; ++i) pixels[i] = Rgb(2.0, 1.0, 0.5);
    const EnvironmentMap map(4, 2, pixels);
    EXPECT_NEAR(map.radiance({0, 0, 1}).x, 2.0, 1e-12);
    EXPECT_NEAR(map.radiance({0, 0, -1}).x, 0.0, 1e-12);
    EXPECT_NEAR(map.radiance({1, 0, 0}).y, 0.5, 1e-12);  // halfway between the rows' centres
}

TEST(EnvironmentMap, RejectsBadPixels) {
    EXPECT_THROW(EnvironmentMap(2, 2, std::vector<Rgb>(3, Rgb(1.0))), InvalidArgument);
    EXPECT_THROW(EnvironmentMap(1, 1, {Rgb(-1.0)}), InvalidArgument);
    EXPECT_THROW(EnvironmentMap(0, 1, {}), InvalidArgument);
}

// Finite is not enough: a lamp of 1e300 W/sr (or DBL_MAX) passed as finite and the bake's sums of it overflowed into
// NaN light, which indexed a table anywhere (tests/fuzz, lamps). Every light is bounded by kMaxLightValue, and a
// lamp's place by 1e9 m.
TEST(Lights, ValuesOverTheBoundAreRefused) {
    const double over = 1e13, most = kMaxLightValue, huge = std::numeric_limits<double>::max();
    EXPECT_NO_THROW(validate(SunLight{{0, 0, 1}, Rgb(most), 0.0}));
    EXPECT_THROW(validate(SunLight{{0, 0, 1}, Rgb(1.0, over, 1.0), 0.0}), InvalidArgument);
    EXPECT_NO_THROW(validate(Sky{Rgb(most), nullptr}));
    EXPECT_THROW(validate(Sky{Rgb(huge), nullptr}), InvalidArgument);
    EXPECT_THROW(EnvironmentMap(1, 1, {Rgb(0.0, 0.0, over)}), InvalidArgument);
    Lamp lamp;
    lamp.emission = Rgb(most);
    EXPECT_NO_THROW(validate(lamp));
    lamp.emission = Rgb(26.0, huge, 44.0);  // lamps seed 132
    EXPECT_THROW(validate(lamp), InvalidArgument);
    lamp.emission = Rgb(1.0, 1.0, std::numeric_limits<double>::quiet_NaN());
    EXPECT_THROW(validate(lamp), InvalidArgument);
    lamp.emission = Rgb(1.0);
    lamp.position = {0.0, 0.0, 1e9};
    EXPECT_NO_THROW(validate(lamp));
    lamp.position = {0.0, 0.0, 1e300};  // finite, and the bake's walks towards it never ended (lamps seed 1370)
    EXPECT_THROW(validate(lamp), InvalidArgument);
    // An area lamp 1e300 m wide: its pieces stood 1e298 m from its centre, and their depths along the beam were
    // inf - inf (lamps seed 29, UBSan). Its size, and any lamp's radius, are bounded as its place is.
    lamp.position = {0.0, 0.0, 1.0};
    lamp.shape = Lamp::Shape::Rectangle;
    lamp.sizeX = lamp.sizeY = 1e9;
    EXPECT_NO_THROW(validate(lamp));
    lamp.sizeX = 1e300;
    EXPECT_THROW(validate(lamp), InvalidArgument);
    lamp.shape = Lamp::Shape::Point;
    lamp.radius = 1e300;
    EXPECT_THROW(validate(lamp), InvalidArgument);
}

TEST(Sky, MapIsScaledByRadiance) {
    Sky sky{Rgb(0.5), std::make_shared<EnvironmentMap>(1, 1, std::vector<Rgb>{Rgb(2.0, 4.0, 6.0)})};
    const Rgb L = sky.radianceFrom({0, 1, 0});
    EXPECT_DOUBLE_EQ(L.x, 1.0);
    EXPECT_DOUBLE_EQ(L.z, 3.0);
}

TEST(SunLight, DiscSamplesStayInTheDisc) {
    const SunLight sun{glm::normalize(glm::dvec3(0.2, 0.1, 1.0)), Rgb(1.0), 0.1};
    for (int i = 0; i < 100; ++i) {
        const glm::dvec3 w = sampleSunDirection(sun, (i + 0.5) / 100.0, std::fmod(i * 0.618, 1.0));
        EXPECT_NEAR(glm::length(w), 1.0, 1e-12);
        EXPECT_LE(std::acos(std::min(1.0, glm::dot(w, sun.direction))), 0.05 + 1e-9);
    }
    EXPECT_THROW(validate(SunLight{{0, 0, 2}, Rgb(1.0), 0.0}), InvalidArgument);
    EXPECT_THROW(validate(SunLight{{0, 0, 1}, Rgb(-1.0), 0.0}), InvalidArgument);
}

}  // namespace firn
