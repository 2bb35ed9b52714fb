#pragma once

#include "firn/util/color.h"

namespace firn {

// What light transport needs to know about snow, per unit density. The optics model (snowOptics, snow_optics.h)
// derives it from grain size and impurities; CUSTOM materials give it directly.
struct VolumeOptics {
    double extinctionPerDensity = 0.0;  // m^2/kg: sigma_t (1/m) = extinctionPerDensity * density (kg/m^3)
    Rgb albedo{1.0};                    // single-scattering albedo omega per channel
    double g = 0.0;                     // Henyey-Greenstein asymmetry of the phase function
};

}  // namespace firn
