#pragma once

#include "firn/optics/spectrum.h"

namespace firn {

// Pure ice, 390-800 nm, from the Warren & Brandt (2008) table compiled into the core
// (cpp/data/ice_optical_constants_wb2008.csv).

struct ComplexIndex {
    double n = 1.0;      // real part: phase velocity ratio
    double kappa = 0.0;  // imaginary part: absorption
};

// Complex refractive index of ice at a wavelength (m). InvalidArgument outside 390-800 nm.
ComplexIndex iceRefractiveIndex(double wavelength);

// Absorption coefficient of bulk ice, gamma = 4 pi kappa / lambda (1/m), at a wavelength (m).
double iceAbsorption(double wavelength);

// gamma (1/m) at every grid wavelength.
const Spectrum &iceAbsorptionSpectrum();

}  // namespace firn
