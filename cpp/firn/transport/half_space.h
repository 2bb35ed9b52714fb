#pragma once

#include <cstdint>
#include <functional>
#include <limits>

namespace firn {

// Plane-parallel, homogeneous media with a Henyey-Greenstein phase function, in optical-depth units:
// the textbook problems the bake is checked against (independent of any grid).

// How a slab answers light falling on its top.
struct SlabResponse {
    double reflectance = 0.0;           // fraction of the incident flux leaving through the top
    double transmittance = 0.0;         // fraction leaving through the bottom, uncollided beam included
    double reflectanceError = 0.0;      // standard errors of the two fractions
    double transmittanceError = 0.0;
};

// Monte Carlo photon transport through a slab of optical thickness tau (infinity: semi-infinite), lit by a
// collimated beam at cos(zenith) mu0, or by a uniform diffuse sky when mu0 <= 0. Analog absorption, so
// both fractions are plain binomial estimates. Deterministic for a seed.
SlabResponse slabMonteCarlo(double omega, double g, double tau, double mu0, long photons, std::uint64_t seed);

// Asymptotic radiative transfer for a semi-infinite medium, omega close to 1 (Kokhanovsky & Zege 2004,
// "Scattering optics of snow", Appl. Opt. 43(7)): y = 4 sqrt((1 - omega) / (3 (1 - g))).
double artSphericalAlbedo(double omega, double g);          // r_s = exp(-y)
double artPlaneAlbedo(double omega, double g, double mu0);  // r_p = exp(-y u(mu0))
// The escape function u(mu) = 3/7 (1 + 2 mu): the angular shape (normalized: 2 int u mu dmu = 1) of light
// that leaves a weakly absorbing medium from deep inside.
inline double escapeFunction(double mu) { return 3.0 / 7.0 * (1.0 + 2.0 * mu); }

// One photon's walk through a slab (tau may be infinite) with analog absorption. Calls onExit(mu, phi,
// top) when it leaves (mu = |cos| to the normal, phi = azimuth from the incident beam's forward
// direction, rad), or onLost(depth) when it is absorbed or, being deeper than maxDepth (optical depth),
// is handed back to the caller. Returns the number of scattering events.
long walkPhoton(double omega, double g, double tau, double mu0, double maxDepth, double u0, double u1,
                const std::function<double()> &uniform,
                const std::function<void(double mu, double phi, bool top)> &onExit,
                const std::function<void(double depth)> &onLost);

}  // namespace firn
