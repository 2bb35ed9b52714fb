#pragma once

// What one ice sphere does to light in ray (geometric) optics, and what a packing of such spheres implies as a
// volume: the sigma_t, omega and g to compare with Kokhanovsky & Zege (2004).
#include "firn/util/color.h"

namespace firn {

// Ray optics of a smooth sphere of index eta, absorption coefficient gamma (1/m) and radius r (m): a parallel
// beam over the sphere's cross-section pi r^2 is split into the reflected ray (p = 0) and rays that leave after
// p - 1 internal reflections (van de Hulst 1957, ch. 12; Bohren & Huffman 1983, section 7.2):
//   weight_0 = R,  weight_p = (1 - R)^2 R^(p-1) exp(-gamma 2 r cos(theta_t) p)
//   deviation_0 = pi - 2 theta_i,  deviation_p = 2 (theta_i - theta_t) + (p - 1) (pi - 2 theta_t)
// integrated over the impact parameter. No diffraction: its extinction efficiency is 1, not 2.
struct SphereRayOptics {
    double absorptionEfficiency = 0.0;  // Q_abs: absorbed power over the power falling on pi r^2
    double g = 0.0;                     // mean cosine of the scattering angle of the scattered power
};

SphereRayOptics sphereRayOptics(double eta, double gamma, double radius);

// Volume optics of spheres at ice volume fraction f in geometric optics, with or without the diffraction peak.
// Without: sigma_t = f 3 / (4 r) (Q_ext = 1), omega = 1 - Q_abs, g = g_rays. With diffraction (Q_ext = 2, half
// the extinction scattered into a forward peak of cosine ~1): sigma_t doubles, 1 - omega halves, g = (1 + g_rays) / 2.
// Both give the same similarity-scaled sigma_t (1 - g) and (1 - omega) / (1 - g), hence the same albedo.
struct PackedSphereOptics {
    double sigmaT = 0.0;    // 1/m
    double omega = 1.0;     // single-scattering albedo
    double g = 0.0;         // asymmetry
};

PackedSphereOptics packedSphereOptics(const SphereRayOptics &sphere, double volumeFraction, double radius,
                                      bool withDiffraction);

// Ice absorption per Rec.709 channel (1/m) for grains of radius r (m), from the Warren & Brandt 2008 spectrum
// the way the rest of the core makes RGB (snow_optics.h: the channel's co-albedo is the one whose white-sky
// albedo is the channel's), turned back into the gamma that gives that co-albedo: gamma = 3 (1 - omega) / (2 B r).
// Radii outside snow's 1 um - 10 mm use the nearest end of that range.
Rgb iceAbsorptionRgb(double radius);

}  // namespace firn

namespace firn {

// KZ04's asymptotic albedo of a deep packing of spheres, per channel, from the spheres' own ray optics (omega and
// g without diffraction; the similarity relation makes the choice immaterial): the plane albedo at mu0 = 1, or
// with `diffuse` the spherical (white-sky) albedo.
Rgb kz04SpherePileAlbedo(double eta, const Rgb &gamma, double radius, bool diffuse = false);

}  // namespace firn
