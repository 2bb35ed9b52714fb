#include "firn/optics/snow_optics.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "firn/optics/color_matching.h"
#include "firn/optics/ice_optics.h"
#include "firn/optics/impurities.h"
#include "firn/optics/kz04.h"
#include "firn/optics/water_absorption.h"
#include "firn/util/error.h"

namespace firn {

namespace {

void require(bool ok, const std::string &what, double value, const char *unit) {
    if (ok) return;
    std::ostringstream message;
    message << what << ", got " << value << unit;
    throw InvalidArgument(message.str());
}

// Volume fraction of the snow that is ice (m^3/m^3).
double iceVolumeFraction(const SnowParameters &snow) {
    return (snow.density - kWaterDensity * snow.liquidWater) / kIceDensity;
}

// 1 - omega at one wavelength from the absorption coefficients there (1/m) and the impurity MACs (m^2/kg).
double coAlbedoFrom(const SnowParameters &snow, double gammaIce, double gammaWater, double macBlackCarbon,
                    double macDust) {
    const double phi_i = iceVolumeFraction(snow);
    const double sigma_t = 3.0 * phi_i / (2.0 * snow.grainRadius);
    const double sigma_a = snow.B * (phi_i * gammaIce + snow.liquidWater * gammaWater) +
                           snow.density * (snow.blackCarbon * macBlackCarbon + snow.dust * macDust);
    return sigma_a / sigma_t;
}

void requireWeakAbsorption(double beta, double wavelength) {
    if (beta < 1.0) return;
    std::ostringstream message;
    message << "the impurities absorb more than the snow extinguishes at " << wavelength * 1e9
            << " nm (1 - omega = " << beta << "): lower black carbon or dust";
    throw InvalidArgument(message.str());
}

}  // namespace

double grainRadiusFromSsa(double ssa) {
    require(std::isfinite(ssa) && ssa > 0.0, "specific surface area must be positive (m^2/kg)", ssa, " m^2/kg");
    return 3.0 / (kIceDensity * ssa);
}

void validate(const SnowParameters &snow) {
    require(std::isfinite(snow.grainRadius) && snow.grainRadius >= 1e-6 && snow.grainRadius <= 0.01,
            "grain radius must be within 1 um - 10 mm (optical radius of the ice grains, in metres)",
            snow.grainRadius, " m");
    require(std::isfinite(snow.density) && snow.density > 0.0 && snow.density <= kIceDensity,
            "snow density must be within (0, 917] kg/m^3", snow.density, " kg/m^3");
    require(std::isfinite(snow.blackCarbon) && snow.blackCarbon >= 0.0 && snow.blackCarbon < 1.0,
            "black carbon must be a mass fraction within [0, 1) (1 ng/g = 1e-9)", snow.blackCarbon, "");
    require(std::isfinite(snow.dust) && snow.dust >= 0.0 && snow.dust < 1.0,
            "dust must be a mass fraction within [0, 1) (1 ug/g = 1e-6)", snow.dust, "");
    require(std::isfinite(snow.liquidWater) && snow.liquidWater >= 0.0 && snow.liquidWater < 1.0,
            "liquid water must be a volume fraction within [0, 1)", snow.liquidWater, "");
    if (!(iceVolumeFraction(snow) > 0.0)) {
        std::ostringstream message;
        message << "liquid water fraction " << snow.liquidWater << " weighs " << kWaterDensity * snow.liquidWater
                << " kg/m^3, leaving no ice in snow of density " << snow.density
                << " kg/m^3 (need liquid water < density / 1000)";
        throw InvalidArgument(message.str());
    }
    require(std::isfinite(snow.B) && snow.B > 0.0 && snow.B <= 5.0,
            "absorption enhancement B must be within (0, 5] (1.25 spheres, 1.6 irregular grains)", snow.B, "");
    require(std::isfinite(snow.g) && snow.g > -1.0 && snow.g < 1.0, "asymmetry g must be within (-1, 1)", snow.g,
            "");
}

double extinctionPerDensity(const SnowParameters &snow) {
    validate(snow);
    if (snow.liquidWater == 0.0) return 3.0 / (2.0 * kIceDensity * snow.grainRadius);  // exact for dry snow
    return 3.0 * iceVolumeFraction(snow) / (2.0 * snow.grainRadius * snow.density);
}

double coAlbedo(const SnowParameters &snow, double wavelength) {
    validate(snow);
    const double beta =
        coAlbedoFrom(snow, iceAbsorption(wavelength), waterAbsorption(wavelength),
                     massAbsorption(kBlackCarbon, wavelength), massAbsorption(kMineralDust, wavelength));
    requireWeakAbsorption(beta, wavelength);
    return beta;
}

Spectrum coAlbedoSpectrum(const SnowParameters &snow) {
    validate(snow);
    Spectrum beta{};
    for (std::size_t i = 0; i < kSpectrumSamples; ++i) {
        const double wavelength = spectrumWavelengthNm(i) * 1e-9;
        beta[i] = coAlbedoFrom(snow, iceAbsorptionSpectrum()[i], waterAbsorptionSpectrum()[i],
                               massAbsorption(kBlackCarbon, wavelength), massAbsorption(kMineralDust, wavelength));
        requireWeakAbsorption(beta[i], wavelength);
    }
    return beta;
}

VolumeOptics snowOptics(const SnowParameters &snow) {
    const Spectrum beta = coAlbedoSpectrum(snow);
    Spectrum whiteSky{};
    for (std::size_t i = 0; i < kSpectrumSamples; ++i) whiteSky[i] = kz04SphericalAlbedo(beta[i], snow.g);
    const Rgb channelWhiteSky = reflectanceToRgb(whiteSky);

    // A channel darker than ART allows even at omega = 0 happens only for absurd impurity loads.
    const double darkest = kz04SphericalAlbedo(1.0, snow.g);

    VolumeOptics optics;
    optics.extinctionPerDensity = extinctionPerDensity(snow);
    for (int c = 0; c < 3; ++c)
        optics.albedo[c] = 1.0 - kz04CoAlbedo(std::max(channelWhiteSky[c], darkest), snow.g);
    optics.g = snow.g;
    return optics;
}

}  // namespace firn
