#pragma once

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace firn {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInvFourPi = 1.0 / (4.0 * kPi);

// An orthonormal frame around a unit vector n (Duff et al. 2017, "Building an orthonormal basis, revisited").
struct Frame {
    glm::dvec3 t, b, n;
    explicit Frame(const glm::dvec3 &normal) : n(normal) {
        const double sign = std::copysign(1.0, n.z);
        const double a = -1.0 / (sign + n.z);
        const double c = n.x * n.y * a;
        t = glm::dvec3(1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x);
        b = glm::dvec3(c, sign + n.y * n.y * a, -n.y);
    }
    glm::dvec3 toWorld(double x, double y, double z) const { return x * t + y * b + z * n; }
};

// Direction at angle acos(cosTheta) from axis, azimuth phi (rad).
inline glm::dvec3 directionAround(const glm::dvec3 &axis, double cosTheta, double phi) {
    const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
    return Frame(axis).toWorld(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta);
}

// Cosine-weighted hemisphere around n: pdf = cos / pi (1/sr).
inline glm::dvec3 sampleCosineHemisphere(const glm::dvec3 &n, double u1, double u2) {
    return directionAround(n, std::sqrt(1.0 - u1), 2.0 * kPi * u2);
}

// Uniform over the cone of half-angle acos(cosMax) around axis.
inline glm::dvec3 sampleUniformCone(const glm::dvec3 &axis, double cosMax, double u1, double u2) {
    return directionAround(axis, 1.0 - u1 * (1.0 - cosMax), 2.0 * kPi * u2);
}

// Henyey-Greenstein phase function (1/sr), normalized over the sphere; cosTheta is the cosine between the
// propagation directions before and after scattering.
inline double henyeyGreenstein(double cosTheta, double g) {
    const double denom = 1.0 + g * g - 2.0 * g * cosTheta;
    return kInvFourPi * (1.0 - g * g) / (denom * std::sqrt(denom));
}

// Samples the cosine of the scattering angle from Henyey-Greenstein (exact inversion; pbrt-v4 §11.3.1).
inline double sampleHenyeyGreensteinCos(double g, double u) {
    if (std::abs(g) < 1e-3) return 1.0 - 2.0 * u;
    const double s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u);
    return std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
}

// New propagation direction after scattering a photon travelling along `direction`.
inline glm::dvec3 sampleHenyeyGreenstein(const glm::dvec3 &direction, double g, double u1, double u2) {
    return directionAround(direction, sampleHenyeyGreensteinCos(g, u1), 2.0 * kPi * u2);
}

}  // namespace firn
