#pragma once

// Reflection and refraction at a smooth dielectric interface (ice and air), for unpolarised light.
#include <algorithm>
#include <cmath>
#include <optional>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace firn {

// Fraction of unpolarised power reflected (Kr; Kt = 1 - Kr) at an interface, for light arriving at
// cos(incidence) cosThetaI > 0 from the side of index n_i onto index n_t, eta = n_t / n_i (ice from air:
// 1.31; air from ice: 1 / 1.31). The mean of the s and p Fresnel equations (Born & Wolf, section 1.5.3):
//   r_s = (n_i cos_i - n_t cos_t) / (n_i cos_i + n_t cos_t),  r_p = (n_t cos_i - n_i cos_t) / (n_t cos_i + n_i cos_t)
//   Kr = (r_s^2 + r_p^2) / 2.  Total internal reflection (sin_t > 1) gives Kr = 1.
inline double fresnelReflectance(double cosThetaI, double eta) {
    cosThetaI = std::clamp(cosThetaI, 0.0, 1.0);
    const double sin2ThetaT = (1.0 - cosThetaI * cosThetaI) / (eta * eta);
    if (sin2ThetaT >= 1.0) return 1.0;
    const double cosThetaT = std::sqrt(1.0 - sin2ThetaT);
    const double rs = (cosThetaI - eta * cosThetaT) / (cosThetaI + eta * cosThetaT);
    const double rp = (eta * cosThetaI - cosThetaT) / (eta * cosThetaI + cosThetaT);
    return 0.5 * (rs * rs + rp * rp);
}

// Mirror direction of unit `direction` about unit normal n.
inline glm::dvec3 reflect(const glm::dvec3 &direction, const glm::dvec3 &n) {
    return direction - 2.0 * glm::dot(direction, n) * n;
}

// Refracted unit direction (Snell), with n facing the incoming side (dot(direction, n) < 0) and eta = n_t / n_i;
// none under total internal reflection.
inline std::optional<glm::dvec3> refract(const glm::dvec3 &direction, const glm::dvec3 &n, double eta) {
    const double cosThetaI = -glm::dot(direction, n);
    const double sin2ThetaT = (1.0 - cosThetaI * cosThetaI) / (eta * eta);
    if (sin2ThetaT >= 1.0) return std::nullopt;
    const double cosThetaT = std::sqrt(1.0 - sin2ThetaT);
    return glm::normalize(direction / eta + (cosThetaI / eta - cosThetaT) * n);
}

}  // namespace firn
