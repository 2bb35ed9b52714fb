#pragma once

#include "firn/util/color.h"
#include "firn/optics/volume_optics.h"

namespace firn {

// Length scales and looks that follow from a medium's optics at a density: what an artist can judge
// (how deep light goes, how white the snow is) instead of omega = 0.99998.

// InvalidArgument unless extinction >= 0, 0 <= omega <= 1 per channel and -1 < g < 1.
void validate(const VolumeOptics &optics);

// Extinction coefficient sigma_t (1/m) at a density (kg/m^3).
double sigmaT(const VolumeOptics &optics, double density);

// Transport mean free path l* = 1 / (sigma_a + sigma_s (1 - g)) = 1 / (sigma_t (1 - omega g)) (m): the
// distance after which light has forgotten its direction.
Rgb transportMeanFreePath(const VolumeOptics &optics, double density);

// Diffusion length L_d = 1 / sqrt(3 sigma_a (sigma_a + sigma_s (1 - g))) (m): the e-folding depth of diffuse
// light deep in the snow (KZ04's asymptotic attenuation coefficient is its inverse). Infinite for omega = 1.
Rgb diffusionLength(const VolumeOptics &optics, double density);

// White-sky (spherical) albedo of a deep layer, per channel, by KZ04 asymptotic radiative transfer.
Rgb whiteSkyAlbedo(const VolumeOptics &optics);

}  // namespace firn
