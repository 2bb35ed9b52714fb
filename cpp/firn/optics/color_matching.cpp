#include "firn/optics/color_matching.h"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "firn/optics/data/cie_illuminant_d65.h"

namespace firn {

namespace {

constexpr auto &kD65Table = data::kCieIlluminantD65;  // wavelength_nm, relative_power
static_assert(std::size(kD65Table) == kSpectrumSamples && onSpectrumGrid(kD65Table),
              "the D65 table must hold exactly the spectral grid's wavelengths");

// One lobe of the Wyman-Sloan-Shirley fit: a Gaussian with different inverse widths below and above its peak.
double lobe(double nm, double peak, double inverseWidthBelow, double inverseWidthAbove) {
    const double t = (nm - peak) * (nm < peak ? inverseWidthBelow : inverseWidthAbove);
    return std::exp(-0.5 * t * t);
}

// CIE XYZ of the chromaticity (x, y) at luminance Y = 1.
glm::dvec3 xyzOfChromaticity(double x, double y) { return {x / y, 1.0, (1.0 - x - y) / y}; }

// Linear Rec.709 RGB -> XYZ: columns are the primaries, scaled so that RGB (1, 1, 1) is the D65 white.
glm::dmat3 rec709ToXyz() {
    const glm::dmat3 primaries(xyzOfChromaticity(0.64, 0.33), xyzOfChromaticity(0.30, 0.60),
                               xyzOfChromaticity(0.15, 0.06));
    const glm::dvec3 scale = glm::inverse(primaries) * xyzOfChromaticity(0.3127, 0.3290);
    return glm::dmat3(primaries[0] * scale.x, primaries[1] * scale.y, primaries[2] * scale.z);
}

}  // namespace

glm::dvec3 cie1931Xyz(double nm) {
    // Wyman, Sloan & Shirley (2013), listing 1 (multi-lobe fit of the 1931 2-degree functions).
    const double x = 0.362 * lobe(nm, 442.0, 0.0624, 0.0374) + 1.056 * lobe(nm, 599.8, 0.0264, 0.0323) -
                     0.065 * lobe(nm, 501.1, 0.0490, 0.0382);
    const double y = 0.821 * lobe(nm, 568.8, 0.0213, 0.0247) + 0.286 * lobe(nm, 530.9, 0.0613, 0.0322);
    const double z = 1.217 * lobe(nm, 437.0, 0.0845, 0.0278) + 0.681 * lobe(nm, 459.0, 0.0385, 0.0725);
    return {x, y, z};
}

const glm::dmat3 &xyzToRec709() {
    static const glm::dmat3 m = glm::inverse(rec709ToXyz());
    return m;
}

double rec709Luminance(const Rgb &rgb) {
    static const glm::dmat3 toXyz = rec709ToXyz();
    return (toXyz * rgb).y;
}

const std::array<Rgb, kSpectrumSamples> &rec709Weights() {
    static const std::array<Rgb, kSpectrumSamples> weights = [] {
        std::array<Rgb, kSpectrumSamples> w{};
        Rgb sum(0.0);
        for (std::size_t i = 0; i < kSpectrumSamples; ++i) {
            const double trapezoid = (i == 0 || i + 1 == kSpectrumSamples) ? 0.5 : 1.0;
            const double illuminant = kD65Table[i][1];
            w[i] = trapezoid * illuminant * (xyzToRec709() * cie1931Xyz(spectrumWavelengthNm(i)));
            sum += w[i];
        }
        for (Rgb &wi : w) wi /= sum;
        return w;
    }();
    return weights;
}

Rgb spectrumToRgb(const Spectrum &spectrum) {
    Rgb rgb(0.0);
    for (std::size_t i = 0; i < kSpectrumSamples; ++i) rgb += spectrum[i] * rec709Weights()[i];
    return rgb;
}

Rgb reflectanceToRgb(const Spectrum &reflectance) {
    const Rgb rgb = spectrumToRgb(reflectance);
    const double y = std::clamp(rec709Luminance(rgb), 0.0, 1.0);
    // Largest fraction of the colour's distance from grey that keeps every channel within [0, 1].
    double keep = 1.0;
    for (int c = 0; c < 3; ++c) {
        if (rgb[c] > 1.0) keep = std::min(keep, (1.0 - y) / (rgb[c] - y));
        if (rgb[c] < 0.0) keep = std::min(keep, y / (y - rgb[c]));
    }
    const Rgb mapped = Rgb(y) + keep * (rgb - Rgb(y));
    return glm::clamp(mapped, Rgb(0.0), Rgb(1.0));  // rounding only
}

}  // namespace firn
