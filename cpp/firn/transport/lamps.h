#pragma once

#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "firn/util/color.h"

namespace firn {

// A lamp at a finite distance: Blender's Point, Spot and Area lamps, with Cycles 3.4's emission.
//   Point, Spot: a sphere of `radius` (0: a point) of intensity I (W/sr); Blender: Power P (W) x Color
//     gives I = P / (4 pi) (measured in Cycles: tests/blender/test_lamps.py). A Spot keeps the light
//     within its cone: I(theta) = I cos(theta) smoothstep(0, (1 - cos(a/2)) blend, cos(theta) - cos(a/2))
//     with theta from the axis, a the cone's full angle (Cycles 3.4's spot_attenuation, cosine included).
//   Rectangle, Ellipse: a one-sided Lambertian emitter facing `axis`, sizeX x sizeY (m; an ellipse's
//     diameters), of radiance L (W/m^2/sr); Blender: L = P / (4 A) x Color, A its area.
struct Lamp {
    enum class Shape { Point, Spot, Rectangle, Ellipse };
    Shape shape = Shape::Point;
    glm::dvec3 position{0.0};           // m, world: the centre
    glm::dvec3 axis{0.0, 0.0, -1.0};    // unit: where a Spot or area lamp shines (Blender: the lamp's -Z)
    glm::dvec3 tangent{1.0, 0.0, 0.0};  // unit, perpendicular to axis: an area lamp's size X direction
    Rgb emission{0.0};                  // Point, Spot: intensity I (W/sr); Rectangle, Ellipse: radiance L (W/m^2/sr)
    double radius = 0.0;                // m, Point and Spot
    double spotAngle = 0.0;             // rad, full cone angle (0, pi]
    double spotBlend = 0.0;             // 0..1
    double sizeX = 0.0, sizeY = 0.0;    // m, area lamps

    bool isArea() const { return shape == Shape::Rectangle || shape == Shape::Ellipse; }
    double area() const;  // m^2, an area lamp's
};

// Light from one point of a lamp reaching x: an unbiased one-sample estimate of the lamp's irradiance.
struct LampSample {
    glm::dvec3 direction{0.0, 0.0, 1.0};  // unit, from x towards the sampled point on the lamp
    double distance = 0.0;                // m
    Rgb irradiance{0.0};                  // W/m^2 on a plane facing `direction`, before anything in between
};

// Samples a point of the lamp (uniform over a sphere's disc facing x, or over the area) with (u1, u2)
// uniform in [0, 1)^2.
LampSample sampleLamp(const Lamp &lamp, const glm::dvec3 &x, double u1, double u2);

// An area lamp near the snow as pieces, each a beam from its own direction: the bake lights the snow by each light's
// direction from the point lit, so a large lamp near the snow, seen whole from its centre, left the patches facing
// away from that centre unlit though they see part of it (ball_grey under a 40 cm square 10 cm away: the render's
// bias -31 %; in 2 x 2, 4 x 4 or 8 x 8 pieces -6, -7, -6 %: docs/benchmarks.md, ramp-lamps).
// Pieces across each side (x, y) that keep each at most twice `distance` (m, from the lamp's centre to the nearest
// snow) wide, at most kMaxLampPiecesAcross (2 x 2 already holds the figures above); (1, 1) for a Point or Spot.
constexpr int kMaxLampPiecesAcross = 4;
glm::ivec2 lampPiecesAcross(const Lamp &lamp, double distance);
// The lamp as across.x x across.y equal rectangles of its radiance ((1, 1), a Point or a Spot: the lamp itself); an
// Ellipse's as the cells whose centres lie inside it, their radiance scaled to keep its power.
std::vector<Lamp> lampPieces(const Lamp &lamp, const glm::ivec2 &across);

// Throws InvalidArgument naming the bad field.
void validate(const Lamp &lamp);

}  // namespace firn
