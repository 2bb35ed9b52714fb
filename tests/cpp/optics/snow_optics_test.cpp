#include "firn/optics/snow_optics.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "firn/optics/color_matching.h"
#include "firn/optics/ice_optics.h"
#include "firn/optics/kz04.h"
#include "firn/optics/transport_scales.h"
#include "firn/optics/water_absorption.h"
#include "firn/util/error.h"

namespace firn {

namespace {

SnowParameters snow(double grainRadius, double blackCarbon = 0.0, double dust = 0.0, double liquidWater = 0.0,
                    double density = 300.0) {
    SnowParameters p;
    p.grainRadius = grainRadius;
    p.density = density;
    p.blackCarbon = blackCarbon;
    p.dust = dust;
    p.liquidWater = liquidWater;
    return p;
}

Rgb whiteSky(const SnowParameters &p) { return whiteSkyAlbedo(snowOptics(p)); }

}  // namespace

// --- KZ04 albedos -----------------------------------------------------------------------------------------

TEST(Kz04, ReproducesSnowopticsRegression) {
    // snowoptics (Picard) regression test: KZ04, B = 1.6, g = 0.845, Warren & Brandt 2008 ice at 800 nm,
    // solar zenith 45 deg, SSA 20 m^2/kg, 10 % diffuse light -> 0.8905460508683.
    SnowParameters p;
    p.grainRadius = grainRadiusFromSsa(20.0);
    const double mu0 = std::cos(45.0 * M_PI / 180.0);
    EXPECT_NEAR(kz04Albedo(coAlbedo(p, 800e-9), p.g, mu0, 0.1), 0.8905460508683, 1e-5);
}

TEST(Kz04, AgreesWithExactSemiInfiniteMedium) {
    // Exact spherical and plane albedos of a semi-infinite Henyey-Greenstein medium (adding-doubling and
    // H-functions, Monte Carlo to ~0.1 %; /work/shared/notes/snow-optics.md). KZ04 claims < 0.5 % for y < 0.5.
    struct Row {
        double g, omega, sphericalAlbedo, plane1, planeHalf;
    };
    const Row exact[] = {{0.0, 0.999, 0.92971, 0.91285, 0.93806},
                         {0.87, 0.999, 0.81791, 0.77340, 0.83926},
                         {0.87, 0.9999, 0.93810, 0.92182, 0.94594}};
    for (const Row &row : exact) {
        const double beta = 1.0 - row.omega;
        ASSERT_LT(kz04Y(beta, row.g), 0.5);
        EXPECT_NEAR(kz04SphericalAlbedo(beta, row.g) / row.sphericalAlbedo, 1.0, 5e-3) << row.g << " " << row.omega;
        EXPECT_NEAR(kz04PlaneAlbedo(beta, row.g, 1.0) / row.plane1, 1.0, 5e-3) << row.g << " " << row.omega;
        EXPECT_NEAR(kz04PlaneAlbedo(beta, row.g, 0.5) / row.planeHalf, 1.0, 5e-3) << row.g << " " << row.omega;
    }
}

TEST(Kz04, CoAlbedoInvertsSphericalAlbedo) {
    for (double beta : {1e-8, 1e-6, 1e-4, 1e-2, 0.3})
        for (double g : {0.0, 0.845, 0.93})
            EXPECT_NEAR(kz04CoAlbedo(kz04SphericalAlbedo(beta, g), g) / beta, 1.0, 1e-9);
}

TEST(Kz04, RejectsImpossibleInputs) {
    EXPECT_THROW(kz04SphericalAlbedo(-1e-3, 0.8), InvalidArgument);
    EXPECT_THROW(kz04SphericalAlbedo(1e-3, 1.0), InvalidArgument);
    EXPECT_THROW(kz04PlaneAlbedo(1e-3, 0.8, 0.0), InvalidArgument);   // sun on the horizon
    EXPECT_THROW(kz04Albedo(1e-3, 0.8, 0.5, 1.5), InvalidArgument);   // diffuse fraction > 1
    EXPECT_THROW(kz04CoAlbedo(1e-6, 0.845), InvalidArgument);         // darker than omega = 0 allows
}

// --- ice and water ----------------------------------------------------------------------------------------

TEST(IceOptics, AbsorptionFromWarrenBrandt) {
    // gamma = 4 pi kappa / lambda with Warren & Brandt (2008) kappa: 9.239e-11 (450), 2.289e-9 (550),
    // 1.43e-8 (650 nm).
    EXPECT_NEAR(iceAbsorption(450e-9), 4 * M_PI * 9.239e-11 / 450e-9, 1e-12);
    EXPECT_NEAR(iceAbsorption(550e-9), 4 * M_PI * 2.289e-9 / 550e-9, 1e-10);
    EXPECT_NEAR(iceAbsorption(650e-9), 4 * M_PI * 1.43e-8 / 650e-9, 1e-9);
    EXPECT_NEAR(iceRefractiveIndex(550e-9).n, 1.311, 1e-12);
}

TEST(IceOptics, InterpolatesKappaLogarithmically) {
    // Between 450 and 460 nm kappa is read on a straight line in log space: the geometric mean at 455 nm.
    EXPECT_NEAR(iceRefractiveIndex(455e-9).kappa / std::sqrt(9.239e-11 * 1.325e-10), 1.0, 1e-12);
    EXPECT_THROW(iceAbsorption(380e-9), InvalidArgument);
    EXPECT_THROW(iceAbsorption(810e-9), InvalidArgument);
    EXPECT_NO_THROW(iceAbsorption(800e-9));
}

TEST(WaterAbsorption, PopeAndFry) {
    // Pope & Fry (1997): 0.00922 (450), 0.0565 (550), 0.340 (650) 1/m. Water absorbs more than ice in the blue.
    EXPECT_DOUBLE_EQ(waterAbsorption(450e-9), 0.00922);
    EXPECT_DOUBLE_EQ(waterAbsorption(550e-9), 0.0565);
    EXPECT_DOUBLE_EQ(waterAbsorption(650e-9), 0.340);
    EXPECT_GT(waterAbsorption(450e-9), 2.0 * iceAbsorption(450e-9));
}

// --- snow optics ------------------------------------------------------------------------------------------

TEST(SnowOptics, ExtinctionIsGeometricOptics) {
    // sigma_t = 3 rho / (2 rho_ice r) for dry snow (Q_ext = 2): r = 100 um, rho = 300 kg/m^3.
    const SnowParameters p = snow(100e-6);
    EXPECT_DOUBLE_EQ(snowOptics(p).extinctionPerDensity * 300.0, 3.0 * 300.0 / (2.0 * 917.0 * 100e-6));
    EXPECT_DOUBLE_EQ(sigmaT(snowOptics(p), 300.0), 3.0 * 300.0 / (2.0 * 917.0 * 100e-6));
}

TEST(SnowOptics, CoAlbedoIsKokhanovskyZege) {
    // Dry clean snow: 1 - omega = (2/3) B gamma r; soot adds (2 / SSA) c MAC (KZ04; Bond & Bergstrom 2006).
    SnowParameters p = snow(200e-6);
    EXPECT_NEAR(coAlbedo(p, 600e-9) / (2.0 / 3.0 * 1.6 * iceAbsorption(600e-9) * 200e-6), 1.0, 1e-12);
    p.blackCarbon = 100e-9;
    const double ssa = 3.0 / (917.0 * 200e-6);
    const double soot = 2.0 / ssa * 100e-9 * 7500.0;  // at 550 nm, MAC 7.5 m^2/g
    EXPECT_NEAR(coAlbedo(p, 550e-9) / (2.0 / 3.0 * 1.6 * iceAbsorption(550e-9) * 200e-6 + soot), 1.0, 1e-12);
}

TEST(SnowOptics, FreshCleanSnowIsWhiteAndSlightlyBlue) {
    for (double r : {50e-6, 100e-6}) {
        const Rgb a = whiteSky(snow(r));
        for (int c = 0; c < 3; ++c) EXPECT_GT(a[c], 0.95) << "channel " << c << ", r = " << r;
        EXPECT_GE(a.b, a.g);
        EXPECT_GE(a.g, a.r);
        // Real clean snow: 1 - omega between about 1e-7 and 1e-4 in the visible.
        const Rgb omega = snowOptics(snow(r)).albedo;
        for (int c = 0; c < 3; ++c) {
            EXPECT_LT(1.0 - omega[c], 1e-4);
            EXPECT_GT(1.0 - omega[c], 1e-8);
        }
    }
}

TEST(SnowOptics, RgbAlbedoRendersTheSpectrumsColour) {
    // Per channel, the white-sky albedo of the RGB omega is the colour-matched spectral white-sky albedo.
    const SnowParameters p = snow(300e-6, 50e-9, 20e-6);
    const Spectrum beta = coAlbedoSpectrum(p);
    Spectrum spectral{};
    for (std::size_t i = 0; i < kSpectrumSamples; ++i) spectral[i] = kz04SphericalAlbedo(beta[i], p.g);
    const Rgb expected = reflectanceToRgb(spectral), actual = whiteSky(p);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(actual[c], expected[c], 1e-12);
}

TEST(SnowOptics, BlackCarbonLowersAlbedoMonotonically) {
    Rgb previous(1.0);
    for (double ngPerG : {0.0, 1.0, 10.0, 100.0, 1000.0, 10000.0}) {
        const Rgb a = whiteSky(snow(100e-6, ngPerG * 1e-9));
        for (int c = 0; c < 3; ++c) EXPECT_LT(a[c], previous[c]) << ngPerG << " ng/g, channel " << c;
        previous = a;
    }
}

TEST(SnowOptics, LargerGrainsLowerAlbedo) {
    Rgb previous(1.0);
    for (double r : {30e-6, 50e-6, 100e-6, 200e-6, 500e-6, 1000e-6, 2000e-6}) {
        const Rgb a = whiteSky(snow(r));
        for (int c = 0; c < 3; ++c) EXPECT_LT(a[c], previous[c]) << "r = " << r << ", channel " << c;
        previous = a;
    }
}

TEST(SnowOptics, DustTurnsSnowOrange) {
    // Dust absorbs as lambda^-3: it darkens blue most, so dusty snow is red > green > blue.
    const Rgb clean = whiteSky(snow(300e-6)), dusty = whiteSky(snow(300e-6, 0.0, 500e-6));
    EXPECT_GT(dusty.r, dusty.g);
    EXPECT_GT(dusty.g, dusty.b);
    for (int c = 0; c < 3; ++c) EXPECT_LT(dusty[c], clean[c]);
    EXPECT_GT(clean.b - dusty.b, clean.r - dusty.r);
}

TEST(SnowOptics, LiquidWaterCoarsensGrainsAndAbsorbs) {
    const double r = 500e-6, rho = 400.0, theta = 0.05;
    const SnowParameters dry = snow(r, 0, 0, 0.0, rho), wet = snow(r, 0, 0, theta, rho);
    // The water adds mass but no surface: sigma_t stays that of the ice grains, sigma_t / rho drops.
    const double phi_i = (rho - 1000.0 * theta) / 917.0;
    EXPECT_NEAR(extinctionPerDensity(wet) * rho, 3.0 * phi_i / (2.0 * r), 1e-9);
    // At 550 nm, where water and ice absorb alike (0.0565 vs 0.0523 1/m), wet snow is dry snow with grains
    // coarsened by (phi_i + theta) / phi_i ...
    SnowParameters coarse = dry;
    coarse.grainRadius = r * (phi_i + theta) / phi_i;
    EXPECT_NEAR(coAlbedo(wet, 550e-9) / coAlbedo(coarse, 550e-9), 1.0, 0.01);
    // ... and in the blue, where water absorbs 3.6 times more than ice (450 nm), it is darker still: the water
    // is 12 % of the condensed volume here, so 1 - omega rises by ~30 % over the coarsened dry snow.
    EXPECT_GT(coAlbedo(wet, 450e-9), 1.25 * coAlbedo(coarse, 450e-9));
    // More water, lower albedo in every channel.
    Rgb previous(1.0);
    for (double w : {0.0, 0.02, 0.05, 0.1}) {
        const Rgb a = whiteSky(snow(r, 0, 0, w, rho));
        for (int c = 0; c < 3; ++c) EXPECT_LT(a[c], previous[c]) << w;
        previous = a;
    }
    // Dry snow: density does not matter.
    EXPECT_DOUBLE_EQ(snowOptics(snow(r, 0, 0, 0.0, 100.0)).albedo.r, snowOptics(snow(r, 0, 0, 0.0, 500.0)).albedo.r);
}

TEST(SnowOptics, RejectsWhatIsNotSnow) {
    auto rejects = [](SnowParameters p, const char *words) {
        try {
            snowOptics(p);
            ADD_FAILURE() << "accepted: " << words;
        } catch (const InvalidArgument &e) {
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        }
    };
    SnowParameters p = snow(100e-6);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    rejects(snow(-100e-6), "grain radius");
    rejects(snow(0.0), "grain radius");
    rejects(snow(nan), "grain radius");
    rejects(snow(100e-6, 0, 0, 0, -5.0), "density");
    rejects(snow(100e-6, 0, 0, 0, 1000.0), "density");
    rejects(snow(100e-6, -1e-9), "black carbon");
    rejects(snow(100e-6, 0, -1e-6), "dust");
    rejects(snow(100e-6, 0, 0, -0.01), "liquid water");
    rejects(snow(100e-6, 0, 0, 0.3, 250.0), "leaving no ice");           // 300 kg/m^3 of water in 250
    rejects(snow(1e-3, 0.05), "impurities absorb more");
    p.g = 1.0;
    rejects(p, "asymmetry");
    p = snow(100e-6);
    p.B = 0.0;
    rejects(p, "absorption enhancement");
    EXPECT_THROW(grainRadiusFromSsa(-3.0), InvalidArgument);
}

// --- derived scales ---------------------------------------------------------------------------------------

TEST(TransportScales, FollowTheirDefinitions) {
    VolumeOptics o;
    o.extinctionPerDensity = 10.0;
    o.albedo = Rgb(0.9, 0.99, 1.0);
    o.g = 0.5;
    const double sigma_t = 10.0 * 200.0;
    const Rgb l = transportMeanFreePath(o, 200.0), d = diffusionLength(o, 200.0);
    EXPECT_DOUBLE_EQ(l.r, 1.0 / (sigma_t * (1.0 - 0.9 * 0.5)));
    EXPECT_DOUBLE_EQ(d.r, 1.0 / std::sqrt(3.0 * sigma_t * 0.1 * sigma_t * (1.0 - 0.9 * 0.5)));
    EXPECT_TRUE(std::isinf(d.b));  // no absorption: diffuse light is never extinguished
    o.albedo = Rgb(1.1, 0.5, 0.5);
    EXPECT_THROW(validate(o), InvalidArgument);
    o.albedo = Rgb(0.5);
    EXPECT_THROW(sigmaT(o, -1.0), InvalidArgument);
}

TEST(TransportScales, RealSnowScales) {
    // Fresh snow, r = 100 um at 250 kg/m^3: transport mean free path about 1/(sigma_t (1 - g)) ~ 1.6 mm,
    // diffuse light dies over centimetres to decimetres, red first (the blue glow in snow holes).
    const VolumeOptics o = snowOptics(snow(100e-6));
    const Rgb l = transportMeanFreePath(o, 250.0), d = diffusionLength(o, 250.0);
    EXPECT_NEAR(l.g, 1.0 / (o.extinctionPerDensity * 250.0 * (1.0 - o.g)), 1e-3 * l.g);
    EXPECT_GT(d.r, 0.02);
    EXPECT_LT(d.r, d.g);
    EXPECT_LT(d.g, d.b);
    // KZ04 ties the two: white-sky albedo exp(-y) with y = 4 / (3 sigma_t (1 - g) L_d) as omega -> 1.
    const double sigma_t = sigmaT(o, 250.0);
    const double y = -std::log(whiteSkyAlbedo(o).g);
    EXPECT_NEAR(y, 4.0 / (3.0 * sigma_t * (1.0 - o.g) * d.g), 1e-3 * y);
}

}  // namespace firn
