#include "firn/transport/lights.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

bool isLightValue(const Rgb &c) {
    const auto inRange = [](double v) { return v >= 0.0 && v <= kMaxLightValue; };  // false for NaN
    return inRange(c.x) && inRange(c.y) && inRange(c.z);
}

glm::dvec3 sampleSunDirection(const SunLight &sun, double u1, double u2) {
    if (sun.angularDiameter <= 0.0) return sun.direction;
    return sampleUniformCone(sun.direction, std::cos(0.5 * sun.angularDiameter), u1, u2);
}

EnvironmentMap::EnvironmentMap(int width, int height, std::vector<Rgb> pixels)
    : width_(width), height_(height), pixels_(std::move(pixels)) {
    if (width < 1 || height < 1) throw InvalidArgument("sky map must be at least 1 x 1 pixels");
    if (pixels_.size() != static_cast<std::size_t>(width) * height)
        throw InvalidArgument("sky map has " + std::to_string(pixels_.size()) + " pixels, expected " +
                              std::to_string(width) + " x " + std::to_string(height));
    for (const Rgb &p : pixels_)
        if (!isLightValue(p))
            throw InvalidArgument("sky map pixels must be radiances from 0 to 1e12 (W/m^2/sr)");
}

glm::dvec2 EnvironmentMap::uvFromDirection(const glm::dvec3 &d) {
    const double u = 0.5 - std::atan2(d.y, d.x) / (2.0 * kPi);
    const double v = 0.5 + std::asin(std::clamp(d.z / glm::length(d), -1.0, 1.0)) / kPi;
    return {u, v};
}

glm::dvec3 EnvironmentMap::directionFromUv(double u, double v) {
    const double phi = 2.0 * kPi * (0.5 - u);  // azimuth from +X towards +Y
    const double elevation = kPi * (v - 0.5);
    return {std::cos(elevation) * std::cos(phi), std::cos(elevation) * std::sin(phi), std::sin(elevation)};
}

Rgb EnvironmentMap::radiance(const glm::dvec3 &direction) const {
    const glm::dvec2 uv = uvFromDirection(direction);
    const double x = uv.x * width_ - 0.5, y = std::clamp(uv.y * height_ - 0.5, 0.0, height_ - 1.0);
    const double fx = std::floor(x), fy = std::floor(y);
    const double tx = x - fx, ty = y - fy;
    auto wrap = [this](int i) { return ((i % width_) + width_) % width_; };
    const int x0 = wrap(static_cast<int>(fx)), x1 = wrap(static_cast<int>(fx) + 1);
    const int y0 = static_cast<int>(fy), y1 = std::min(y0 + 1, height_ - 1);
    return (1.0 - ty) * ((1.0 - tx) * pixel(x0, y0) + tx * pixel(x1, y0)) +
           ty * ((1.0 - tx) * pixel(x0, y1) + tx * pixel(x1, y1));
}

Rgb Sky::radianceFrom(const glm::dvec3 &direction) const {
    return map ? radiance * map->radiance(direction) : radiance;
}

bool Sky::isBlack() const { return radiance == Rgb(0.0); }

void validate(const SunLight &sun) {
    const double length = glm::length(sun.direction);
    if (!std::isfinite(length) || std::abs(length - 1.0) > 1e-6)
        throw InvalidArgument("sun direction must be a unit vector");
    if (!isLightValue(sun.irradiance)) throw InvalidArgument("sun irradiance must be from 0 to 1e12 (W/m^2)");
    if (!std::isfinite(sun.angularDiameter) || sun.angularDiameter < 0.0 || sun.angularDiameter > kPi / 2)
        throw InvalidArgument("sun angular diameter must be between 0 and pi/2 rad");
}

void validate(const Sky &sky) {
    if (!isLightValue(sky.radiance)) throw InvalidArgument("sky radiance must be from 0 to 1e12 (W/m^2/sr)");
}

}  // namespace firn
