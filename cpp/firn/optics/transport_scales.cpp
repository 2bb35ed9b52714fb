#include "firn/optics/transport_scales.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "firn/optics/kz04.h"
#include "firn/util/error.h"

namespace firn {

namespace {

void requireDensity(double density) {
    if (std::isfinite(density) && density >= 0.0) return;
    std::ostringstream message;
    message << "density must be >= 0 kg/m^3, got " << density;
    throw InvalidArgument(message.str());
}

}  // namespace

void validate(const VolumeOptics &optics) {
    std::ostringstream message;
    if (!(std::isfinite(optics.extinctionPerDensity) && optics.extinctionPerDensity >= 0.0))
        message << "extinction per density must be >= 0 m^2/kg, got " << optics.extinctionPerDensity;
    else if (!(optics.albedo.r >= 0.0 && optics.albedo.r <= 1.0 && optics.albedo.g >= 0.0 && optics.albedo.g <= 1.0 &&
               optics.albedo.b >= 0.0 && optics.albedo.b <= 1.0))
        message << "single-scattering albedo must be within 0-1 in every channel, got (" << optics.albedo.r << ", "
                << optics.albedo.g << ", " << optics.albedo.b << ")";
    else if (!(optics.g > -1.0 && optics.g < 1.0))
        message << "anisotropy g must be within (-1, 1), got " << optics.g;
    else
        return;
    throw InvalidArgument(message.str());
}

double sigmaT(const VolumeOptics &optics, double density) {
    validate(optics);
    requireDensity(density);
    return optics.extinctionPerDensity * density;
}

Rgb transportMeanFreePath(const VolumeOptics &optics, double density) {
    const double sigma_t = sigmaT(optics, density);
    return Rgb(1.0) / (sigma_t * (Rgb(1.0) - optics.albedo * optics.g));
}

Rgb diffusionLength(const VolumeOptics &optics, double density) {
    const double sigma_t = sigmaT(optics, density);
    Rgb length;
    for (int c = 0; c < 3; ++c) {
        const double sigma_a = sigma_t * (1.0 - optics.albedo[c]);
        const double sigma_tr = sigma_t * (1.0 - optics.albedo[c] * optics.g);
        const double product = 3.0 * sigma_a * sigma_tr;
        length[c] = product > 0.0 ? 1.0 / std::sqrt(product) : std::numeric_limits<double>::infinity();
    }
    return length;
}

Rgb whiteSkyAlbedo(const VolumeOptics &optics) {
    validate(optics);
    Rgb albedo;
    for (int c = 0; c < 3; ++c) albedo[c] = kz04SphericalAlbedo(1.0 - optics.albedo[c], optics.g);
    return albedo;
}

}  // namespace firn
