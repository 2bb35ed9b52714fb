#include "firn/optics/spectrum.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "firn/util/error.h"

namespace firn {

double sampleSpectrum(const Spectrum &values, double wavelength, Interpolation mode) {
    const double nm = wavelength * 1e9;
    // A little slack so 800e-9 m (which is 800.0000000000001 nm in binary) is still in the band.
    const double slack = 1e-9;
    if (!(nm >= kSpectrumFirstNm - slack && nm <= kSpectrumLastNm + slack)) {
        std::ostringstream message;
        message << "wavelength must be within " << kSpectrumFirstNm << "-" << kSpectrumLastNm
                << " nm (the visible band of Firn's optical tables), got " << wavelength << " m";
        throw InvalidArgument(message.str());
    }
    const double x = std::clamp((nm - kSpectrumFirstNm) / kSpectrumStepNm, 0.0, double(kSpectrumSamples - 1));
    const std::size_t i = std::min(std::size_t(x), kSpectrumSamples - 2);
    const double t = x - double(i);
    if (mode == Interpolation::Logarithmic)
        return std::exp((1.0 - t) * std::log(values[i]) + t * std::log(values[i + 1]));
    return (1.0 - t) * values[i] + t * values[i + 1];
}

}  // namespace firn
