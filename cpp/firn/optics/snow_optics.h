#pragma once

#include "firn/optics/spectrum.h"
#include "firn/optics/volume_optics.h"

namespace firn {

// From what snow is made of to what light transport needs: extinction per unit density, single-scattering
// albedo per Rec.709 channel and the phase-function asymmetry g.
//
// Model: Kokhanovsky & Zege (2004), geometric optics of large, weakly absorbing, irregular grains, with pure
// ice from Warren & Brandt (2008). With rho_ice = 917 kg/m^3, phi_i the ice volume fraction, r the optical
// grain radius (r = 3 / (rho_ice SSA)):
//   sigma_t = 3 phi_i / (2 r)                                   (1/m; Q_ext = 2, dry snow: rho SSA / 2)
//   sigma_a = B (phi_i gamma_ice + theta_w gamma_water) + rho (c_BC MAC_BC + c_dust MAC_dust)
//   1 - omega = sigma_a / sigma_t                               (dry, clean: (2/3) B gamma_ice r)
// Liquid water (theta_w, volume fraction of the snow) sits in the necks between grains (pendular regime): it
// joins the grains optically (ice n = 1.31 and water n = 1.33 barely scatter at their interface), so each
// grain grows in volume without gaining surface, r_eff = r (phi_i + theta_w) / phi_i, and absorbs with water's
// own coefficient (Pope & Fry 1997), 1-4 times ice's in the visible. docs/optics.md explains the choices.
//
// RGB: the spectral white-sky albedo r_s(lambda) = exp(-4 sqrt((1 - omega) / (3 (1 - g)))) is integrated into
// Rec.709 channels (color_matching.h) and each channel's omega is the one whose white-sky albedo is that
// channel's: rendered in RGB, the snow has the colour of the real spectrum. Averaging omega itself would not
// do: albedo depends on sqrt(1 - omega), and 1 - omega varies 100-fold across a channel.

inline constexpr double kIceDensity = 917.0;     // kg/m^3
inline constexpr double kWaterDensity = 1000.0;  // kg/m^3

struct SnowParameters {
    double grainRadius = 100e-6;  // m: optical (effective) radius of the ice grains, 3 / (rho_ice SSA)
    double density = 300.0;       // kg/m^3: mass of ice and liquid water per volume of snow
    double blackCarbon = 0.0;     // kg/kg: mass fraction of black carbon in the snow (1 ng/g = 1e-9)
    double dust = 0.0;            // kg/kg: mass fraction of mineral dust in the snow (1 ug/g = 1e-6)
    double liquidWater = 0.0;     // m^3/m^3: liquid water volume fraction of the snow (theta_w)
    double B = 1.6;               // absorption enhancement of the grain shape (~1.25 spheres, 1.6 irregular)
    double g = 0.845;             // asymmetry of the phase function (KZ04: 0.845 irregular grains)
};

// Optical grain radius (m) of snow with a specific surface area (m^2/kg): r = 3 / (rho_ice SSA).
double grainRadiusFromSsa(double ssa);

// InvalidArgument with a clear message when parameters are not snow (negative radius, more water than the
// density holds, g outside (-1, 1), ...).
void validate(const SnowParameters &snow);

// sigma_t / rho (m^2/kg). Dry snow: 3 / (2 rho_ice r), independent of density.
double extinctionPerDensity(const SnowParameters &snow);

// 1 - omega at a wavelength (m) in 390-800 nm.
double coAlbedo(const SnowParameters &snow, double wavelength);

// 1 - omega at every grid wavelength.
Spectrum coAlbedoSpectrum(const SnowParameters &snow);

// The coefficients for rendering and baking (RGB as explained above).
VolumeOptics snowOptics(const SnowParameters &snow);

}  // namespace firn
