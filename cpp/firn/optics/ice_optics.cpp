#include "firn/optics/ice_optics.h"

#include <cmath>

#include "firn/optics/data/ice_optical_constants_wb2008.h"

namespace firn {

namespace {

constexpr auto &kTable = data::kIceOpticalConstantsWb2008;  // wavelength_nm, n, kappa
static_assert(std::size(kTable) == kSpectrumSamples && onSpectrumGrid(kTable),
              "the ice table must hold exactly the spectral grid's wavelengths");

constexpr Spectrum kN = spectrumColumn(kTable, 1);
constexpr Spectrum kKappa = spectrumColumn(kTable, 2);

double absorptionFromKappa(double kappa, double wavelength) { return 4.0 * M_PI * kappa / wavelength; }

}  // namespace

ComplexIndex iceRefractiveIndex(double wavelength) {
    // kappa rises ~7000-fold over the band, close to exponentially: interpolate it in log space.
    return {sampleSpectrum(kN, wavelength, Interpolation::Linear),
            sampleSpectrum(kKappa, wavelength, Interpolation::Logarithmic)};
}

double iceAbsorption(double wavelength) {
    return absorptionFromKappa(iceRefractiveIndex(wavelength).kappa, wavelength);
}

const Spectrum &iceAbsorptionSpectrum() {
    static const Spectrum gamma = [] {
        Spectrum s{};
        for (std::size_t i = 0; i < kSpectrumSamples; ++i)
            s[i] = absorptionFromKappa(kKappa[i], spectrumWavelengthNm(i) * 1e-9);
        return s;
    }();
    return gamma;
}

}  // namespace firn
