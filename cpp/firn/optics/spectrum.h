#pragma once

#include <array>
#include <cstddef>

namespace firn {

// Firn's optics live on one spectral grid: the visible band 390-800 nm in 10 nm steps, the grid of the
// Warren & Brandt (2008) ice table. The CIE colour-matching functions are below 0.4 % of their peaks
// outside it, so colour integrals lose nothing that matters.
inline constexpr double kSpectrumFirstNm = 390.0;  // nm
inline constexpr double kSpectrumStepNm = 10.0;    // nm
inline constexpr std::size_t kSpectrumSamples = 42;
inline constexpr double kSpectrumLastNm = kSpectrumFirstNm + kSpectrumStepNm * (kSpectrumSamples - 1);

// One value per grid wavelength.
using Spectrum = std::array<double, kSpectrumSamples>;

constexpr double spectrumWavelengthNm(std::size_t i) { return kSpectrumFirstNm + kSpectrumStepNm * double(i); }

// A measured table (first column: wavelength in nm) whose rows are exactly the grid's wavelengths.
template <std::size_t Columns>
constexpr bool onSpectrumGrid(const double (&table)[kSpectrumSamples][Columns]) {
    for (std::size_t i = 0; i < kSpectrumSamples; ++i)
        if (table[i][0] != spectrumWavelengthNm(i)) return false;
    return true;
}

// One column of such a table as a Spectrum.
template <std::size_t Columns>
constexpr Spectrum spectrumColumn(const double (&table)[kSpectrumSamples][Columns], std::size_t column) {
    Spectrum s{};
    for (std::size_t i = 0; i < kSpectrumSamples; ++i) s[i] = table[i][column];
    return s;
}

// How to read a sampled spectrum between grid points: absorption spans decades across the band and is
// close to exponential in wavelength, so it interpolates in log space.
enum class Interpolation { Linear, Logarithmic };

// The spectrum at any wavelength (m) of the band; InvalidArgument outside 390-800 nm.
double sampleSpectrum(const Spectrum &values, double wavelength, Interpolation mode);

}  // namespace firn
