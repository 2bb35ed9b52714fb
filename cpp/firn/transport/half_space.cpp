#include "firn/transport/half_space.h"

#include <cmath>

#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

long walkPhoton(double omega, double g, double tau, double mu0, double maxDepth, double u0, double u1,
                const std::function<double()> &uniform,
                const std::function<void(double, double, bool)> &onExit,
                const std::function<void(double)> &onLost) {
    // Depth z grows downwards; the beam travels along +x horizontally, so phi = 0 is "forward".
    const double mu = mu0 > 0.0 ? mu0 : std::sqrt(u0);  // diffuse sky: cosine-weighted incidence
    const double phi0 = mu0 > 0.0 ? 0.0 : 2.0 * kPi * u1;
    const double s0 = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    glm::dvec3 d(s0 * std::cos(phi0), s0 * std::sin(phi0), mu);
    double z = 0.0;
    for (long events = 0;; ++events) {
        z -= std::log(1.0 - uniform()) * d.z;
        if (z < 0.0) {
            onExit(-d.z, std::atan2(d.y, d.x), true);
            return events;
        }
        if (z > tau) {
            onExit(d.z, std::atan2(d.y, d.x), false);
            return events;
        }
        if (z > maxDepth || uniform() >= omega) {
            onLost(z);
            return events;
        }
        d = sampleHenyeyGreenstein(d, g, uniform(), uniform());
    }
}

SlabResponse slabMonteCarlo(double omega, double g, double tau, double mu0, long photons, std::uint64_t seed) {
    Rng rng(seed, 0);
    const std::function<double()> uniform = [&rng] { return rng.uniform(); };
    long reflected = 0, transmitted = 0;
    for (long i = 0; i < photons; ++i)
        walkPhoton(
            omega, g, tau, mu0, std::numeric_limits<double>::infinity(), rng.uniform(), rng.uniform(), uniform,
            [&](double, double, bool top) { ++(top ? reflected : transmitted); }, [](double) {});
    SlabResponse out;
    const double n = double(photons);
    out.reflectance = reflected / n;
    out.transmittance = transmitted / n;
    out.reflectanceError = std::sqrt(out.reflectance * (1.0 - out.reflectance) / n);
    out.transmittanceError = std::sqrt(out.transmittance * (1.0 - out.transmittance) / n);
    return out;
}

double artSphericalAlbedo(double omega, double g) {
    return std::exp(-4.0 * std::sqrt((1.0 - omega) / (3.0 * (1.0 - g))));
}

double artPlaneAlbedo(double omega, double g, double mu0) {
    return std::exp(-4.0 * std::sqrt((1.0 - omega) / (3.0 * (1.0 - g))) * escapeFunction(mu0));
}

}  // namespace firn
