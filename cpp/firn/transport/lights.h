#pragma once

#include <memory>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "firn/util/color.h"

namespace firn {

// A distant disc light, Blender's Sun lamp.
struct SunLight {
    glm::dvec3 direction{0.0, 0.0, 1.0};  // unit, world space, from the scene towards the sun
    Rgb irradiance{0.0};                  // W/m^2 on a plane facing the sun (Blender: Strength x Color)
    double angularDiameter = 0.0;         // rad, full apex angle of the disc (Blender: Angle); 0 = point-like
};

// A direction towards the sun, uniform over its disc; (u1, u2) uniform in [0, 1)^2.
glm::dvec3 sampleSunDirection(const SunLight &sun, double u1, double u2);

// Radiance over the sphere of directions as an equirectangular image, in Blender's convention (the
// Environment Texture node with default mapping, world +Z up):
//   u = 0.5 - atan2(y, x) / (2 pi)   (u = 0.5 looks along +X, u = 0.25 along +Y)
//   v = 0.5 + asin(z) / pi           (v = 0 nadir, v = 1 zenith)
// Pixels are stored row by row from v = 0 (bottom) to v = 1 (top), as in Blender's Image.pixels; pixel
// (column i, row j) is centred at ((i + 1/2) / width, (j + 1/2) / height). Bilinear lookup, wrapping in u.
class EnvironmentMap {
  public:
    EnvironmentMap(int width, int height, std::vector<Rgb> pixels);  // W/m^2/sr

    Rgb radiance(const glm::dvec3 &direction) const;
    int width() const { return width_; }
    int height() const { return height_; }

    static glm::dvec2 uvFromDirection(const glm::dvec3 &direction);
    static glm::dvec3 directionFromUv(double u, double v);

  private:
    const Rgb &pixel(int column, int row) const { return pixels_[static_cast<std::size_t>(row) * width_ + column]; }

    int width_, height_;
    std::vector<Rgb> pixels_;
};

// Light arriving from far away in every direction not blocked by the scene: Blender's World.
struct Sky {
    Rgb radiance{0.0};                          // W/m^2/sr; scales the map when there is one
    std::shared_ptr<const EnvironmentMap> map;  // optional

    // Radiance arriving from `direction` (unit, pointing away from the scene).
    Rgb radianceFrom(const glm::dvec3 &direction) const;
    bool isBlack() const;
};

// The largest value a light takes in any channel (W/m^2, W/sr or W/m^2/sr): far above the sun's radiance (2e7 W/m^2/sr)
// and any lamp's, and far enough under DBL_MAX that the bake's sums and squares of it stay finite (a lamp of 1e300
// W/sr passed as finite, and made the bake's surface light NaN).
constexpr double kMaxLightValue = 1e12;
// Whether every channel is finite, non-negative and at most kMaxLightValue.
bool isLightValue(const Rgb &c);

// Throw InvalidArgument with a message naming the bad field.
void validate(const SunLight &sun);
void validate(const Sky &sky);

}  // namespace firn
