#pragma once

#include <array>

#include <glm/mat3x3.hpp>

#include "firn/optics/spectrum.h"
#include "firn/util/color.h"

namespace firn {

// From spectra to the linear Rec.709 RGB that Cycles renders in.
//
// Colour matching: the CIE 1931 2-degree observer, as the multi-lobe piecewise-Gaussian fit of Wyman, Sloan &
// Shirley (2013), "Simple analytic approximations to the CIE XYZ color matching functions", JCGT 2(2), 1-11:
// within about 0.01 of the tabulated functions, whose peaks are 1.0-1.8 (tests/cpp/optics/snow_optics_test.cpp checks).
// Primaries and white: ITU-R BT.709 (= sRGB), D65. A spectrum is treated as a reflectance lit by CIE D65 (the
// white of Rec.709), integrated over the grid with the trapezoid rule, and each channel is normalised so that
// a spectrally flat reflectance maps to exactly equal RGB.

// (x-bar, y-bar, z-bar) of the CIE 1931 observer at a wavelength (nm).
glm::dvec3 cie1931Xyz(double wavelengthNm);

// CIE XYZ -> linear Rec.709 RGB, built from the BT.709 primaries and the D65 white point.
const glm::dmat3 &xyzToRec709();

// Luminance Y of a linear Rec.709 colour: the Y row of the inverse matrix (0.2126, 0.7152, 0.0722).
double rec709Luminance(const Rgb &rgb);

// Per-channel weights on the spectral grid; each channel's weights sum to 1. They are negative in places
// (the Rec.709 primaries cannot match every spectral colour).
const std::array<Rgb, kSpectrumSamples> &rec709Weights();

// The linear projection of a spectrum onto Rec.709 RGB.
Rgb spectrumToRgb(const Spectrum &spectrum);

// RGB of a reflectance spectrum, within the gamut of reflectances [0, 1]. The projection is exact colorimetry;
// only saturated spectra whose projection leaves [0, 1] (heavily dust-laden snow, for one) are desaturated
// towards grey at constant luminance. Channels are not band averages: the negative lobes let a bluish white
// have a blue channel above its brightest wavelength, which is the colour it has.
Rgb reflectanceToRgb(const Spectrum &reflectance);

}  // namespace firn
