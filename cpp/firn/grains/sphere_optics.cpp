#include "firn/grains/sphere_optics.h"

#include <algorithm>
#include <cmath>

#include "firn/optics/fresnel.h"
#include "firn/optics/kz04.h"
#include "firn/optics/snow_optics.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

SphereRayOptics sphereRayOptics(double eta, double gamma, double radius) {
    if (!(eta > 1.0) || !(gamma >= 0.0) || !(radius > 0.0))
        throw InvalidArgument("sphere optics need eta > 1, absorption >= 0 (1/m) and radius > 0 (m)");
    // Midpoint rule in s = (b / r)^2, uniform over the cross-section: sin(theta_i) = sqrt(s).
    constexpr int kSteps = 200000;
    double absorbed = 0.0, scattered = 0.0, scatteredCos = 0.0;
    for (int k = 0; k < kSteps; ++k) {
        const double s = (k + 0.5) / kSteps;
        const double sinI = std::sqrt(s), thetaI = std::asin(sinI), cosI = std::cos(thetaI);
        const double thetaT = std::asin(sinI / eta);
        const double R = fresnelReflectance(cosI, eta);
        const double transmittance = std::exp(-gamma * 2.0 * radius * std::cos(thetaT));  // one chord
        double left = 1.0;  // power not yet scattered or absorbed, of the ray's 1
        auto scatter = [&](double weight, double deviation) {
            scattered += weight, scatteredCos += weight * std::cos(deviation);
            left -= weight;
        };
        scatter(R, kPi - 2.0 * thetaI);
        double inside = 1.0 - R;  // power inside at the start of a chord
        for (int p = 1; inside > 1e-14 && p < 100000; ++p) {
            const double arriving = inside * transmittance;
            scatter(arriving * (1.0 - R), 2.0 * (thetaI - thetaT) + (p - 1) * (kPi - 2.0 * thetaT));
            inside = arriving * R;
        }
        absorbed += left - inside;  // what is still inside after the last chord is negligible (< 1e-14)
    }
    SphereRayOptics optics;
    optics.absorptionEfficiency = std::clamp(absorbed / kSteps, 0.0, 1.0);  // rounding leaves -1e-19 without absorption
    optics.g = scattered > 0.0 ? scatteredCos / scattered : 0.0;
    return optics;
}

PackedSphereOptics packedSphereOptics(const SphereRayOptics &sphere, double volumeFraction, double radius,
                                      bool withDiffraction) {
    // Projected area per volume of spheres: pi r^2 / (4/3 pi r^3) = 3 / (4 r).
    PackedSphereOptics p;
    p.sigmaT = volumeFraction * 3.0 / (4.0 * radius);
    p.omega = 1.0 - sphere.absorptionEfficiency;
    p.g = sphere.g;
    if (withDiffraction) {
        p.sigmaT *= 2.0;
        p.omega = 1.0 - 0.5 * sphere.absorptionEfficiency;
        p.g = 0.5 * (1.0 + sphere.g);
    }
    return p;
}

Rgb iceAbsorptionRgb(double radius) {
    // The band averaging is defined for snow's grains (1 um - 10 mm); gamma barely depends on the radius (0.5 %
    // from 0.1 to 2 mm), so larger or smaller grains take the nearest end of that range.
    SnowParameters snow;
    snow.grainRadius = std::clamp(radius, 1e-6, 0.01);
    radius = snow.grainRadius;
    snow.B = 1.25;  // spheres; gamma does not depend on B to first order (it cancels below)
    snow.g = 0.89;
    const VolumeOptics optics = snowOptics(snow);
    const Rgb coAlbedo = Rgb(1.0) - optics.albedo;
    return coAlbedo * (3.0 / (2.0 * snow.B * radius));
}

}  // namespace firn

namespace firn {

Rgb kz04SpherePileAlbedo(double eta, const Rgb &gamma, double radius, bool diffuse) {
    Rgb albedo;
    for (int c = 0; c < 3; ++c) {
        const SphereRayOptics sphere = sphereRayOptics(eta, gamma[c], radius);
        albedo[c] = diffuse ? kz04SphericalAlbedo(sphere.absorptionEfficiency, sphere.g)
                            : kz04PlaneAlbedo(sphere.absorptionEfficiency, sphere.g, 1.0);
    }
    return albedo;
}

}  // namespace firn
