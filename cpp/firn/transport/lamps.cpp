#include "firn/transport/lamps.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "firn/transport/lights.h"
#include "firn/util/ceil_count.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

double smoothstep(double edge, double x) {
    const double t = std::clamp(x / edge, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// Cycles 3.4's spot_attenuation: the cone, its blend and a cosine; cosTheta from the spot's axis.
double spotFactor(const Lamp &lamp, double cosTheta) {
    const double cosHalf = std::cos(0.5 * lamp.spotAngle);
    if (cosTheta <= cosHalf) return 0.0;
    const double smooth = (1.0 - cosHalf) * lamp.spotBlend;
    return cosTheta * (smooth > 0.0 ? smoothstep(smooth, cosTheta - cosHalf) : 1.0);
}

glm::dvec3 bitangentOf(const Lamp &lamp) { return glm::cross(lamp.axis, lamp.tangent); }

// The point at (u1, u2) of the lamp's sizeX x sizeY rectangle ((0.5, 0.5) its centre), relative to its centre (m).
glm::dvec3 rectanglePoint(const Lamp &lamp, double u1, double u2) {
    return (u1 - 0.5) * lamp.sizeX * lamp.tangent + (u2 - 0.5) * lamp.sizeY * bitangentOf(lamp);
}

// A point uniform over the area lamp, relative to its centre.
glm::dvec3 areaPoint(const Lamp &lamp, double u1, double u2) {
    if (lamp.shape == Lamp::Shape::Rectangle) return rectanglePoint(lamp, u1, u2);
    const glm::dvec3 bitangent = bitangentOf(lamp);
    const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
    return 0.5 * r * (std::cos(phi) * lamp.sizeX * lamp.tangent + std::sin(phi) * lamp.sizeY * bitangent);
}

bool isUnit(const glm::dvec3 &v) { return std::abs(glm::length(v) - 1.0) < 1e-6; }

}  // namespace

double Lamp::area() const {
    return shape == Shape::Ellipse ? 0.25 * kPi * sizeX * sizeY : sizeX * sizeY;
}

LampSample sampleLamp(const Lamp &lamp, const glm::dvec3 &x, double u1, double u2) {
    LampSample s;
    if (!(glm::length(x - lamp.position) > 1e-9)) return s;  // at the lamp's centre: no direction, no light
    glm::dvec3 q = lamp.position;
    double gain = 1.0;  // irradiance per unit emission, times the dimming by the lamp's own geometry
    if (lamp.isArea()) {
        q += areaPoint(lamp, u1, u2);
        s.direction = q - x;
        s.distance = glm::length(s.direction);
        if (!(s.distance > 0.0)) return LampSample{};
        s.direction /= s.distance;
        gain = lamp.area() * std::max(0.0, -glm::dot(lamp.axis, s.direction)) / (s.distance * s.distance);
    } else {
        const glm::dvec3 outward = glm::normalize(x - lamp.position);
        if (lamp.radius > 0.0)  // the sphere seen from x: a disc of its radius facing x
            q += Frame(outward).toWorld(lamp.radius * std::sqrt(u1) * std::cos(2.0 * kPi * u2),
                                        lamp.radius * std::sqrt(u1) * std::sin(2.0 * kPi * u2), 0.0);
        s.direction = q - x;
        s.distance = glm::length(s.direction);
        s.direction /= s.distance;
        gain = std::max(0.0, -glm::dot(outward, s.direction)) / (s.distance * s.distance);
        if (lamp.shape == Lamp::Shape::Spot) gain *= spotFactor(lamp, -glm::dot(lamp.axis, s.direction));
    }
    s.irradiance = lamp.emission * gain;
    return s;
}

glm::ivec2 lampPiecesAcross(const Lamp &lamp, double distance) {
    if (!lamp.isArea()) return glm::ivec2(1);
    const auto across = [&](double size) {  // a distance of 0 (or NaN) takes the most pieces
        return distance > 0.0 ? ceilCount(size / (2.0 * distance), kMaxLampPiecesAcross) : kMaxLampPiecesAcross;
    };
    return {across(lamp.sizeX), across(lamp.sizeY)};
}

std::vector<Lamp> lampPieces(const Lamp &lamp, const glm::ivec2 &across) {
    if (!lamp.isArea() || across == glm::ivec2(1)) return {lamp};
    const int nx = across.x, ny = across.y;
    std::vector<Lamp> pieces;
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j) {
            const double u = (i + 0.5) / nx, v = (j + 0.5) / ny;  // the cell's centre, of the size
            if (lamp.shape == Lamp::Shape::Ellipse && (u - 0.5) * (u - 0.5) + (v - 0.5) * (v - 0.5) > 0.25) continue;
            Lamp piece = lamp;
            piece.shape = Lamp::Shape::Rectangle;
            piece.position += rectanglePoint(lamp, u, v);
            piece.sizeX = lamp.sizeX / nx, piece.sizeY = lamp.sizeY / ny;
            pieces.push_back(piece);
        }
    if (lamp.shape == Lamp::Shape::Ellipse)  // the cells' area to the ellipse's
        for (Lamp &piece : pieces)
            piece.emission *= 0.25 * kPi * nx * ny / double(pieces.size());
    return pieces;
}

void validate(const Lamp &lamp) {
    if (!isLightValue(lamp.emission))
        throw InvalidArgument("lamp emission must be from 0 to 1e12 (W/sr, or W/m^2/sr for area lamps)");
    // A lamp 1e300 m away is finite, and the bake's walks towards it never ended (tests/fuzz, lamps seed 1370).
    constexpr double kFarthest = 1e9;  // m
    if (!(std::abs(lamp.position.x) <= kFarthest && std::abs(lamp.position.y) <= kFarthest &&
          std::abs(lamp.position.z) <= kFarthest))
        throw InvalidArgument("lamp position must be within 1e9 m of the origin on every axis");
    if (!isUnit(lamp.axis) || !isUnit(lamp.tangent) || std::abs(glm::dot(lamp.axis, lamp.tangent)) > 1e-6)
        throw InvalidArgument("lamp axis and tangent must be perpendicular unit vectors");
    // Sizes too: an area lamp's pieces stand half its size from its centre (1e300 m: a NaN depth, lamps seed 29).
    if (!(lamp.radius >= 0.0 && lamp.radius <= kFarthest))
        throw InvalidArgument("lamp radius must be from 0 to 1e9 m");
    if (lamp.shape == Lamp::Shape::Spot &&
        (!(lamp.spotAngle > 0.0 && lamp.spotAngle <= kPi) || !(lamp.spotBlend >= 0.0 && lamp.spotBlend <= 1.0)))
        throw InvalidArgument("spot lamp: angle in (0, pi] rad and blend in [0, 1]");
    if (lamp.isArea() && !(lamp.sizeX > 0.0 && lamp.sizeY > 0.0 && lamp.sizeX <= kFarthest && lamp.sizeY <= kFarthest))
        throw InvalidArgument("area lamp sizes must be positive and at most 1e9 m");
}

}  // namespace firn
