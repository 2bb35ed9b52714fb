#pragma once

#include <cstdint>

namespace firn {

// The angular shape of sun light returned by a thick snow surface, in the form the baked grids store
// (radiance linear in the outgoing direction w):
//   R(w) = pi L(w) / (mu0 E) = a + b (n . w) + c (t . w)
// n the surface normal, t the unit tangent pointing where the sun's light travels (forward), mu0 the
// cosine of the sun's incidence, E its irradiance at normal incidence. It is the reflection function of a
// non-absorbing half-space with a Henyey-Greenstein phase function (all orders), fitted by least squares
// in relative error over the outgoing hemisphere, weighted by projected solid angle, with the flux fixed:
// a + 2b/3 = 1 (all light returns). Absorption is accounted for separately (escape function).
struct SunLobe {
    double a = 1.0, b = 0.0, c = 0.0;
};

// Bilinear in (g, mu0) from the precomputed table (sun_lobe_table.inc), g clamped to [0, 0.95].
SunLobe sunLobe(double g, double mu0);

// The table's source: 1D Monte Carlo of a conservative half-space (photons deeper than 30 transport mean
// free paths leave later with the escape function's shape). Used by tools/sun_lobe_table.cpp.
SunLobe fitSunLobe(double g, double mu0, long photons, std::uint64_t seed);

}  // namespace firn
