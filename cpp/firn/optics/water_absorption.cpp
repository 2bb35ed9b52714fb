#include "firn/optics/water_absorption.h"

#include "firn/optics/data/water_absorption_pf1997.h"

namespace firn {

namespace {

constexpr auto &kTable = data::kWaterAbsorptionPf1997;  // wavelength_nm, absorption_per_m
static_assert(std::size(kTable) == kSpectrumSamples && onSpectrumGrid(kTable),
              "the water table must hold exactly the spectral grid's wavelengths");

constexpr Spectrum kAbsorption = spectrumColumn(kTable, 1);

}  // namespace

double waterAbsorption(double wavelength) {
    return sampleSpectrum(kAbsorption, wavelength, Interpolation::Logarithmic);
}

const Spectrum &waterAbsorptionSpectrum() { return kAbsorption; }

}  // namespace firn
