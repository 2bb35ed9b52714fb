#pragma once

#include "firn/optics/spectrum.h"

namespace firn {

// Pure liquid water, 390-800 nm: Pope & Fry (1997) to 700 nm, Smith & Baker (1981) beyond, compiled into the
// core (cpp/data/water_absorption_pf1997.csv). In the visible, water absorbs 1-4 times more than ice.

// Absorption coefficient of liquid water (1/m) at a wavelength (m). InvalidArgument outside 390-800 nm.
double waterAbsorption(double wavelength);

// The same at every grid wavelength (1/m).
const Spectrum &waterAbsorptionSpectrum();

}  // namespace firn
