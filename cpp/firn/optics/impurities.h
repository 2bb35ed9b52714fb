#pragma once

namespace firn {

// Light-absorbing impurities in snow, as mass absorption cross-sections (MAC, m^2 per kg of impurity) that
// follow a power law in wavelength: MAC(lambda) = MAC(550 nm) (550 nm / lambda)^AAE. They are treated as
// particles between the grains (external mixture): each adds rho * c * MAC to the absorption coefficient.
struct ImpurityAbsorption {
    double mac550 = 0.0;    // m^2/kg at 550 nm
    double angstrom = 0.0;  // absorption Angstrom exponent (AAE)
};

// Black carbon (soot): Bond & Bergstrom (2006) recommend 7.5 m^2/g at 550 nm for fresh, uncoated BC; their
// refractive index 1.95 - 0.79i gives a lambda^-1 law (8.4 / 6.9 / 5.8 m^2/g at 450 / 550 / 650 nm).
// BC inside the grains (internal mixture) absorbs about 1.5 times more (Flanner et al. 2012).
inline constexpr ImpurityAbsorption kBlackCarbon{7500.0, 1.0};

// Mineral dust: weakly absorbing, strongly in the blue (iron oxides), so dusty snow turns orange-brown.
// Saharan dust in the laboratory: mass extinction 3.3-3.7 m^2/g at single-scattering albedo 0.98-0.99 near
// 532 nm, i.e. 0.035-0.07 m^2/g absorption (Linke et al. 2006); AAE 2.5-3.3 for resuspended dusts
// (Caponi et al. 2017). Dust in snow is coarser than airborne dust and absorbs less per mass: 0.04 m^2/g, AAE 3.
inline constexpr ImpurityAbsorption kMineralDust{40.0, 3.0};

// MAC (m^2/kg) at a wavelength (m).
double massAbsorption(const ImpurityAbsorption &impurity, double wavelength);

}  // namespace firn
