// Fresnel reflectance and refraction at the air-ice interface against the textbook forms.
#include <cmath>

#include <gtest/gtest.h>

#include "firn/optics/fresnel.h"
#include "firn/grains/sphere_optics.h"
#include "firn/util/sampling.h"

namespace firn {
namespace {

constexpr double kEta = 1.31;  // ice over air

// Fresnel's sine and tangent laws (Born & Wolf, "Principles of Optics", section 1.5.2, eqs. 21a-21b):
//   r_s = -sin(i - t) / sin(i + t),  r_p = tan(i - t) / tan(i + t): another form than the one in fresnel.h.
double sineTangentLaw(double thetaI, double eta) {
    const double thetaT = std::asin(std::sin(thetaI) / eta);
    const double rs = -std::sin(thetaI - thetaT) / std::sin(thetaI + thetaT);
    const double rp = std::tan(thetaI - thetaT) / std::tan(thetaI + thetaT);
    return 0.5 * (rs * rs + rp * rp);
}

TEST(Fresnel, NormalIncidenceIsTheSquaredIndexContrast) {
    // ((n - 1) / (n + 1))^2 = (0.31 / 2.31)^2 = 0.018010...
    EXPECT_NEAR(fresnelReflectance(1.0, kEta), std::pow(0.31 / 2.31, 2), 1e-12);
    EXPECT_NEAR(fresnelReflectance(1.0, 1.0 / kEta), std::pow(0.31 / 2.31, 2), 1e-12);
}

TEST(Fresnel, MatchesTheSineAndTangentLaws) {
    for (double degrees : {5.0, 20.0, 37.3, 52.6 /* Brewster: atan(1.31) */, 70.0, 85.0, 89.0}) {
        const double theta = degrees * kPi / 180.0;
        EXPECT_NEAR(fresnelReflectance(std::cos(theta), kEta), sineTangentLaw(theta, kEta), 1e-12) << degrees;
    }
}

TEST(Fresnel, ParallelPolarisationVanishesAtBrewstersAngle) {
    // At tan(i) = eta, i + t = 90 deg and r_p = 0, leaving r_s^2 / 2 = sin^2(i - t) / 2.
    const double thetaB = std::atan(kEta), thetaT = 0.5 * kPi - thetaB;
    EXPECT_NEAR(fresnelReflectance(std::cos(thetaB), kEta), 0.5 * std::pow(std::sin(thetaB - thetaT), 2), 1e-12);
}

TEST(Fresnel, TotalInternalReflectionBeyondTheCriticalAngle) {
    const double critical = std::asin(1.0 / kEta);  // 49.76 deg inside ice
    EXPECT_EQ(fresnelReflectance(std::cos(critical + 1e-6), 1.0 / kEta), 1.0);
    EXPECT_LT(fresnelReflectance(std::cos(critical - 1e-3), 1.0 / kEta), 1.0);
    const glm::dvec3 n(0, 0, 1);
    const double beyond = critical + 0.01;
    EXPECT_FALSE(refract(glm::dvec3(std::sin(beyond), 0, -std::cos(beyond)), n, 1.0 / kEta).has_value());
}

TEST(Fresnel, ReciprocityAcrossTheInterface) {
    // The same pair of angles reflects the same fraction from either side (Stokes relations).
    for (double degrees : {10.0, 30.0, 60.0, 80.0}) {
        const double thetaI = degrees * kPi / 180.0, thetaT = std::asin(std::sin(thetaI) / kEta);
        EXPECT_NEAR(fresnelReflectance(std::cos(thetaI), kEta), fresnelReflectance(std::cos(thetaT), 1.0 / kEta), 1e-12);
    }
}

TEST(Fresnel, RefractionFollowsSnell) {
    const glm::dvec3 n(0, 0, 1);
    const double thetaI = 0.7;
    const glm::dvec3 in(std::sin(thetaI), 0, -std::cos(thetaI));
    const glm::dvec3 out = *refract(in, n, kEta);
    EXPECT_NEAR(glm::length(out), 1.0, 1e-12);
    EXPECT_NEAR(std::sin(thetaI), kEta * out.x, 1e-12);  // sin i = eta sin t
    EXPECT_LT(out.z, 0.0);
    const glm::dvec3 mirrored = reflect(in, n);
    EXPECT_NEAR(mirrored.z, std::cos(thetaI), 1e-12);
}

TEST(SphereRayOptics, AbsorptionOfAWeaklyAbsorbingSphere) {
    // Large, weakly absorbing sphere (gamma r << 1): Q_abs = (4/3) gamma r n^2 (1 - (1 - 1/n^2)^(3/2))
    // (Bohren & Huffman 1983, section 7.2; the factor is KZ04's B = 1.25 for spheres of ice).
    const double r = 1e-3, gamma = 0.05;  // gamma r = 5e-5
    const double B = kEta * kEta * (1.0 - std::pow(1.0 - 1.0 / (kEta * kEta), 1.5));
    EXPECT_NEAR(B, 1.2535, 1e-3);
    const SphereRayOptics optics = sphereRayOptics(kEta, gamma, r);
    EXPECT_NEAR(optics.absorptionEfficiency / (4.0 / 3.0 * gamma * r * B), 1.0, 0.01);
    EXPECT_NEAR(sphereRayOptics(kEta, 0.0, r).absorptionEfficiency, 0.0, 1e-12);  // energy conserved
}

TEST(SphereRayOptics, AsymmetryOfIceSpheres) {
    // With diffraction, large ice spheres have g = 0.87-0.89 (Bohren & Barkstrom 1974: 0.874; snow-optics notes).
    const SphereRayOptics optics = sphereRayOptics(kEta, 0.0, 1e-3);
    const PackedSphereOptics withDiffraction = packedSphereOptics(optics, 0.5, 1e-3, true);
    EXPECT_GT(withDiffraction.g, 0.86);
    EXPECT_LT(withDiffraction.g, 0.90);
    EXPECT_NEAR(packedSphereOptics(optics, 0.5, 1e-3, false).sigmaT, 0.5 * 0.75 / 1e-3, 1e-9);
}

}  // namespace
}  // namespace firn
