#include "firn/optics/kz04.h"

#include <cmath>
#include <sstream>

#include "firn/util/error.h"

namespace firn {

namespace {

void checkInputs(double coAlbedo, double g) {
    if (!(coAlbedo >= 0.0 && coAlbedo <= 1.0)) {
        std::ostringstream message;
        message << "co-albedo 1 - omega must be within 0-1, got " << coAlbedo;
        throw InvalidArgument(message.str());
    }
    if (!(g > -1.0 && g < 1.0)) {
        std::ostringstream message;
        message << "asymmetry g must be within (-1, 1), got " << g;
        throw InvalidArgument(message.str());
    }
}

}  // namespace

double kz04Y(double coAlbedo, double g) {
    checkInputs(coAlbedo, g);
    return 4.0 * std::sqrt(coAlbedo / (3.0 * (1.0 - g)));
}

double kz04SphericalAlbedo(double coAlbedo, double g) { return std::exp(-kz04Y(coAlbedo, g)); }

double kz04PlaneAlbedo(double coAlbedo, double g, double mu0) {
    if (!(mu0 > 0.0 && mu0 <= 1.0)) {
        std::ostringstream message;
        message << "cos(solar zenith) must be within (0, 1] (sun above the horizon), got " << mu0;
        throw InvalidArgument(message.str());
    }
    const double u = 3.0 / 7.0 * (1.0 + 2.0 * mu0);  // escape function of ART
    return std::exp(-kz04Y(coAlbedo, g) * u);
}

double kz04Albedo(double coAlbedo, double g, double mu0, double diffuseFraction) {
    if (!(diffuseFraction >= 0.0 && diffuseFraction <= 1.0)) {
        std::ostringstream message;
        message << "diffuse fraction must be within 0-1, got " << diffuseFraction;
        throw InvalidArgument(message.str());
    }
    return (1.0 - diffuseFraction) * kz04PlaneAlbedo(coAlbedo, g, mu0) +
           diffuseFraction * kz04SphericalAlbedo(coAlbedo, g);
}

double kz04CoAlbedo(double sphericalAlbedo, double g) {
    if (!(sphericalAlbedo > 0.0 && sphericalAlbedo <= 1.0)) {
        std::ostringstream message;
        message << "spherical albedo must be within (0, 1], got " << sphericalAlbedo;
        throw InvalidArgument(message.str());
    }
    checkInputs(0.0, g);
    const double y = -std::log(sphericalAlbedo);
    const double coAlbedo = 3.0 * (1.0 - g) * y * y / 16.0;
    if (coAlbedo > 1.0) {
        std::ostringstream message;
        message << "spherical albedo " << sphericalAlbedo << " is darker than any medium at g = " << g
                << " (it would need 1 - omega = " << coAlbedo << " > 1)";
        throw InvalidArgument(message.str());
    }
    return coAlbedo;
}

}  // namespace firn
