#include "firn/transport/lamps.h"

#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/transport/incident_light.h"
#include "firn/transport/scene.h"
#include "firn/util/error.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

// Mean irradiance (W/m^2) onto a surface at x facing n, from many samples of the lamp.
double irradiance(const Lamp &lamp, const glm::dvec3 &x, const glm::dvec3 &n, int samples = 200000) {
    Rng rng(7, 0);
    double sum = 0.0;
    for (int s = 0; s < samples; ++s) {
        const LampSample l = sampleLamp(lamp, x, rng.uniform(), rng.uniform());
        sum += l.irradiance.x * std::max(0.0, glm::dot(n, l.direction));
    }
    return sum / samples;
}

Lamp lampAbove(Lamp::Shape shape, double height) {
    Lamp lamp;
    lamp.shape = shape;
    lamp.position = {0.0, 0.0, height};
    lamp.emission = Rgb(1.0);
    return lamp;
}

}  // namespace

// A point lamp: inverse square and Lambert's cosine.
TEST(Lamp, PointFollowsTheInverseSquareLaw) {
    const Lamp lamp = lampAbove(Lamp::Shape::Point, 2.0);
    EXPECT_NEAR(irradiance(lamp, {0, 0, 0}, {0, 0, 1}, 1), 1.0 / 4.0, 1e-12);
    EXPECT_NEAR(irradiance(lamp, {1, 0, 0}, {0, 0, 1}, 1), 2.0 / std::pow(5.0, 1.5), 1e-12);
}

// A sphere of radius R seen from distance D is a disc facing the point (Cycles 3.4): on a surface facing
// it, averaging I cos^2 / d^2 over the disc gives I / (D^2 + R^2) (integrated by hand).
TEST(Lamp, SphereLampAveragesOverItsDisc) {
    Lamp lamp = lampAbove(Lamp::Shape::Point, 0.5);
    lamp.radius = 0.3;
    const double D = 0.5, R = 0.3, exact = 1.0 / (D * D + R * R);
    EXPECT_NEAR(irradiance(lamp, {0, 0, 0}, {0, 0, 1}) / exact, 1.0, 0.01);
}

// The spot's falloff as Cycles 3.4 renders it, measured there (a diffuse plane 2 m below a spot of Size 90
// degrees, 1 m off its axis): a factor 0.8944 = cos(26.57 deg) with Blend 0, and 0.6296 with Blend 1.
TEST(Lamp, SpotFalloffMatchesCycles) {
    Lamp spot = lampAbove(Lamp::Shape::Spot, 2.0);
    spot.spotAngle = kPi / 2.0;
    const Lamp point = lampAbove(Lamp::Shape::Point, 2.0);
    const glm::dvec3 x(1, 0, 0), up(0, 0, 1);
    EXPECT_NEAR(irradiance(spot, x, up, 1) / irradiance(point, x, up, 1), 0.8944, 2e-4);
    spot.spotBlend = 1.0;
    EXPECT_NEAR(irradiance(spot, x, up, 1) / irradiance(point, x, up, 1), 0.6296, 2e-4);
    EXPECT_EQ(irradiance(spot, {3, 0, 0}, up, 1), 0.0);  // 56 degrees off the axis: outside the 45-degree cone
}

// Area lamps of unit radiance: under a rectangle's centre, four corner view factors (Howell's catalogue,
// C-11: E = L [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))] / 2 per quarter);
// under a disc of radius R at height h, E = pi L R^2 / (h^2 + R^2).
TEST(Lamp, AreaLampsMatchTheirViewFactors) {
    Lamp rectangle = lampAbove(Lamp::Shape::Rectangle, 2.0);
    rectangle.sizeX = 1.0, rectangle.sizeY = 3.0;
    const double X = 0.25, Y = 0.75;
    const double quarter = 0.5 * (X / std::sqrt(1 + X * X) * std::atan(Y / std::sqrt(1 + X * X)) +
                                  Y / std::sqrt(1 + Y * Y) * std::atan(X / std::sqrt(1 + Y * Y)));
    EXPECT_NEAR(irradiance(rectangle, {0, 0, 0}, {0, 0, 1}) / (4.0 * quarter), 1.0, 0.01);
    EXPECT_EQ(irradiance(rectangle, {0, 0, 3}, {0, 0, -1}), 0.0);  // behind it: one-sided

    Lamp disc = lampAbove(Lamp::Shape::Ellipse, 0.5);
    disc.sizeX = disc.sizeY = 1.2;
    EXPECT_NEAR(irradiance(disc, {0, 0, 0}, {0, 0, 1}) / (kPi * 0.36 / (0.25 + 0.36)), 1.0, 0.01);
}

// An area lamp in pieces (the bake's beams near the snow) lights as the whole lamp: under the rectangle's centre
// the sum of its pieces' irradiance is Howell's view factor above, off it the whole lamp's; an ellipse's cells keep
// its power; a Point or Spot stays whole, and a lamp at no distance takes the most pieces.
TEST(Lamp, PiecesLightAsTheWholeLamp) {
    Lamp rectangle = lampAbove(Lamp::Shape::Rectangle, 2.0);
    rectangle.sizeX = 1.0, rectangle.sizeY = 3.0;
    EXPECT_EQ(lampPiecesAcross(rectangle, 2.0), glm::ivec2(1, 1));
    EXPECT_EQ(lampPiecesAcross(rectangle, 0.5), glm::ivec2(1, 3));
    EXPECT_EQ(lampPiecesAcross(rectangle, 0.0), glm::ivec2(kMaxLampPiecesAcross));
    EXPECT_EQ(lampPiecesAcross(rectangle, 1e-300), glm::ivec2(kMaxLampPiecesAcross));  // no overflow of int
    EXPECT_EQ(lampPiecesAcross(lampAbove(Lamp::Shape::Point, 2.0), 0.0), glm::ivec2(1));
    EXPECT_EQ(lampPieces(lampAbove(Lamp::Shape::Spot, 2.0), {3, 3}).size(), 1u);

    const auto sum = [](const std::vector<Lamp> &pieces, const glm::dvec3 &x) {
        double e = 0.0;
        for (const Lamp &piece : pieces) e += irradiance(piece, x, {0, 0, 1});
        return e;
    };
    const std::vector<Lamp> pieces = lampPieces(rectangle, {2, 4});
    ASSERT_EQ(pieces.size(), 8u);
    const double X = 0.25, Y = 0.75;
    const double quarter = 0.5 * (X / std::sqrt(1 + X * X) * std::atan(Y / std::sqrt(1 + X * X)) +
                                  Y / std::sqrt(1 + Y * Y) * std::atan(X / std::sqrt(1 + Y * Y)));
    EXPECT_NEAR(sum(pieces, {0, 0, 0}) / (4.0 * quarter), 1.0, 0.01);
    EXPECT_NEAR(sum(pieces, {1.5, 0.5, 0}) / irradiance(rectangle, {1.5, 0.5, 0}, {0, 0, 1}), 1.0, 0.01);

    Lamp disc = lampAbove(Lamp::Shape::Ellipse, 0.5);
    disc.sizeX = disc.sizeY = 1.2;
    double power = 0.0;  // W/sr per unit radiance of the disc: its area
    const std::vector<Lamp> cells = lampPieces(disc, {4, 4});
    for (const Lamp &cell : cells) power += cell.emission.x * cell.sizeX * cell.sizeY;
    EXPECT_EQ(cells.size(), 12u);  // the 4 corner cells' centres lie outside
    EXPECT_NEAR(power / (kPi * 0.36), 1.0, 1e-12);
}

TEST(Lamp, RejectsBadSettings) {
    Lamp lamp = lampAbove(Lamp::Shape::Spot, 1.0);
    lamp.spotAngle = 4.0;
    EXPECT_THROW(validate(lamp), InvalidArgument);
    lamp = lampAbove(Lamp::Shape::Rectangle, 1.0);
    EXPECT_THROW(validate(lamp), InvalidArgument);  // no size
    lamp = lampAbove(Lamp::Shape::Point, 1.0);
    lamp.emission = Rgb(-1.0);
    EXPECT_THROW(validate(lamp), InvalidArgument);
    lamp.emission = Rgb(1.0);
    lamp.axis = {0, 0, 2};
    EXPECT_THROW(validate(lamp), InvalidArgument);
}

// A voxel face's way to a lamp (faceWayToBeam): a point lamp's from the face itself (its light spreads radially); an
// area lamp's, of half-width a at distance d, turned from the centre's way by d^2 / (d^2 + a^2) of that (on its axis
// a disc's light vector diverges at 2 d / (d^2 + a^2) per unit irradiance, a point's at 2 / d).
TEST(Lamps, AnAreaLampsWayFromAVoxelFaceTurnsLessThanAPointLamps) {
    const glm::dvec3 centre(0.0), face(0.005, 0.0, 0.0);  // m: the +x face of a 1 cm voxel
    Lamp point;
    point.position = glm::dvec3(0.0, 0.0, 0.1);
    Lamp area = point;
    area.shape = Lamp::Shape::Rectangle;
    area.sizeX = area.sizeY = 0.1 * std::sqrt(kPi);  // a^2 = area / pi = d^2: half the point's turn
    Scene scene;
    scene.lamps = {point, area};
    const glm::dvec3 atCentre = towardsBeam(scene, 0, centre), atFace = towardsBeam(scene, 0, face);
    const glm::dvec3 pointWay = faceWayToBeam(scene, 0, centre, face);
    EXPECT_NEAR(glm::length(pointWay - atFace), 0.0, 1e-12);
    const glm::dvec3 areaWay = faceWayToBeam(scene, 1, centre, face);
    EXPECT_NEAR(glm::length(areaWay - glm::normalize(atCentre + 0.5 * (atFace - atCentre))), 0.0, 1e-12);
    EXPECT_GT(glm::length(areaWay - atFace), 0.4 * glm::length(atFace - atCentre));  // not the point's way
}

}  // namespace firn
