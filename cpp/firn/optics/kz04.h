#pragma once

namespace firn {

// Albedos of a semi-infinite, weakly absorbing, optically thick medium by asymptotic radiative transfer (ART),
// Kokhanovsky & Zege (2004), "Scattering optics of snow", Appl. Opt. 43(7), 1589-1602. Inputs: the
// co-albedo 1 - omega of single scattering and the asymmetry g of the phase function. Accurate to < 0.5 % for
// y < 0.5 (omega >= 0.999 at g ~ 0.9); 2-4 % at omega = 0.99.

// y = 4 sqrt((1 - omega) / (3 (1 - g))): the exponent of the spherical albedo.
double kz04Y(double coAlbedo, double g);

// Spherical (white-sky) albedo, for uniform diffuse illumination: r_s = exp(-y).
double kz04SphericalAlbedo(double coAlbedo, double g);

// Plane (black-sky) albedo for a collimated beam at cos(zenith) mu0: r_p = exp(-y u(mu0)), u = 3/7 (1 + 2 mu0).
double kz04PlaneAlbedo(double coAlbedo, double g, double mu0);

// Albedo under a sky that is partly diffuse: (1 - f) r_p(mu0) + f r_s, f the diffuse fraction of irradiance.
double kz04Albedo(double coAlbedo, double g, double mu0, double diffuseFraction);

// The co-albedo 1 - omega whose spherical albedo is r_s (the inverse of kz04SphericalAlbedo):
// 1 - omega = 3 (1 - g) (ln r_s)^2 / 16.
double kz04CoAlbedo(double sphericalAlbedo, double g);

}  // namespace firn
