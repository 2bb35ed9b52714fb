#pragma once

#include <cmath>

namespace firn {

// The soft-object field of Wyvill et al. (1986), used for snow by Nishita et al. (1997): a degree-6
// polynomial of r/R that falls from 1 at the centre to 0 (with zero slope) at radius R.
//   f(u) = 1 - 22/9 u^2 + 17/9 u^4 - 4/9 u^6,  u = r / R <= 1
// Templated on the precision: double for tables, float in the rasterizer's vectorized loops.
template <typename Real>
inline Real wyvillField(Real uSquared) {
    const Real u2 = uSquared, u4 = u2 * u2, u6 = u4 * u2;
    const Real f = Real(1) - Real(22.0 / 9.0) * u2 + Real(17.0 / 9.0) * u4 - Real(4.0 / 9.0) * u6;
    return uSquared >= Real(1) ? Real(0) : f;  // a select, not a branch: loops over voxels vectorize
}

// df/d(u^2): the gradient of the field of a ball at offset d from its centre is 2 slope(u^2) d / R^2.
template <typename Real>
inline Real wyvillFieldSlope(Real uSquared) {
    const Real u2 = uSquared;
    const Real slope = Real(-22.0 / 9.0) + Real(34.0 / 9.0) * u2 - Real(12.0 / 9.0) * u2 * u2;
    return uSquared >= Real(1) ? Real(0) : slope;
}

// Field of an infinite plane layer of balls (radius R, one per area a, m^2), at height z above it,
// averaged over the plane: (2 pi R^2 / a) * integral_{|z|/R}^1 f(u) u du. Used to place layers so that
// the snow's iso-surface sits at the requested depth.
inline double wyvillLayerField(double z, double radius, double areaPerBall) {
    const double u = std::abs(z) / radius;
    if (u >= 1.0) return 0.0;
    // G(u) = integral_0^u f(t) t dt; G(1) = 4/27.
    auto G = [](double t) {
        const double t2 = t * t, t4 = t2 * t2, t6 = t4 * t2, t8 = t4 * t4;
        return t2 / 2.0 - (11.0 / 18.0) * t4 + (17.0 / 54.0) * t6 - t8 / 18.0;
    };
    constexpr double kPi = 3.14159265358979323846;
    return 2.0 * kPi * radius * radius / areaPerBall * (4.0 / 27.0 - G(u));
}

}  // namespace firn
