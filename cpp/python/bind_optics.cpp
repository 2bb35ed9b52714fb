// Snow optics: physical parameters -> extinction, albedo and g for rendering; KZ04 albedos for checking
// against published values; the ice, water and colour tables underneath. All physics is in cpp/firn/.
#include <array>
#include <optional>
#include <sstream>

#include <pybind11/stl.h>

#include "bindings.h"
#include "firn/optics/color_matching.h"
#include "firn/optics/ice_optics.h"
#include "firn/optics/kz04.h"
#include "firn/optics/snow_optics.h"
#include "firn/optics/transport_scales.h"
#include "firn/optics/water_absorption.h"
#include "firn/util/error.h"

namespace py = pybind11;

namespace firncore {

namespace {

py::tuple toTuple(const firn::Rgb &c) { return py::make_tuple(c.r, c.g, c.b); }

// Density for the KZ04 functions when the caller gives none: dry snow's albedo does not depend on it.
constexpr double kNominalDensity = 300.0;  // kg/m^3

// The snow's parameters from Python keywords: grain radius or SSA (exactly one), density optional only where
// it cannot matter (dry snow, albedo only).
firn::SnowParameters snowFrom(std::optional<double> grainRadius, std::optional<double> ssa,
                              std::optional<double> density, double blackCarbon, double dust, double liquidWater,
                              double B, double g, bool densityRequired) {
    if (grainRadius.has_value() == ssa.has_value())
        throw firn::InvalidArgument("give exactly one of grain_radius (m) and ssa (specific surface area, m^2/kg)");
    if (!density && (densityRequired || liquidWater != 0.0))
        throw firn::InvalidArgument(densityRequired ? "density (kg/m^3) is required"
                                                    : "liquid_water needs the snow's density (kg/m^3)");
    firn::SnowParameters snow;
    snow.grainRadius = grainRadius ? *grainRadius : firn::grainRadiusFromSsa(*ssa);
    snow.density = density.value_or(kNominalDensity);
    snow.blackCarbon = blackCarbon;
    snow.dust = dust;
    snow.liquidWater = liquidWater;
    snow.B = B;
    snow.g = g;
    firn::validate(snow);
    return snow;
}

// The keyword arguments every snow function takes, after its own.
#define FIRN_SNOW_KWARGS                                                                                        \
    py::kw_only(), py::arg("grain_radius") = py::none(), py::arg("ssa") = py::none(),                          \
        py::arg("density") = py::none(), py::arg("black_carbon") = 0.0, py::arg("dust") = 0.0,                 \
        py::arg("liquid_water") = 0.0, py::arg("B") = 1.6, py::arg("g") = 0.845

const char *const kSnowArgsDoc = R"doc(
Snow (keywords): grain_radius (m, optical radius of the ice grains) or ssa (specific surface area, m^2/kg):
exactly one; density (kg/m^3, snow incl. liquid water); black_carbon and dust (mass fractions, kg/kg:
1 ng/g = 1e-9, 1 ug/g = 1e-6); liquid_water (volume fraction of the snow); B (absorption enhancement,
1.6 irregular grains, ~1.25 spheres); g (asymmetry, 0.845). Bad values raise ValueError.)doc";

std::string withSnowArgs(const char *doc) { return std::string(doc) + kSnowArgsDoc; }

void bindVolumeOptics(py::module_ &m) {
    py::class_<firn::VolumeOptics>(m, "VolumeOptics", R"doc(
What light transport needs to know about snow, per unit density (immutable):
extinction_per_density (m^2/kg; sigma_t = extinction_per_density * density), albedo (single-scattering
albedo omega per linear Rec.709 channel), g (Henyey-Greenstein asymmetry). Made by firncore.optics() from
physical parameters, or directly: VolumeOptics(extinction_per_density, albedo, g).)doc")
        .def(py::init([](double extinctionPerDensity, std::array<double, 3> albedo, double g) {
                 firn::VolumeOptics optics;
                 optics.extinctionPerDensity = extinctionPerDensity;
                 optics.albedo = firn::Rgb(albedo[0], albedo[1], albedo[2]);
                 optics.g = g;
                 firn::validate(optics);
                 return optics;
             }),
             py::arg("extinction_per_density"), py::arg("albedo"), py::arg("g"))
        .def_property_readonly("extinction_per_density",
                               [](const firn::VolumeOptics &o) { return o.extinctionPerDensity; },
                               "sigma_t per unit density (m^2/kg).")
        .def_property_readonly("albedo", [](const firn::VolumeOptics &o) { return toTuple(o.albedo); },
                               "Single-scattering albedo omega, (R, G, B) linear Rec.709.")
        .def_property_readonly("co_albedo",
                               [](const firn::VolumeOptics &o) { return toTuple(firn::Rgb(1.0) - o.albedo); },
                               "1 - omega per channel: the absorbed fraction per interaction.")
        .def_property_readonly("g", [](const firn::VolumeOptics &o) { return o.g; },
                               "Henyey-Greenstein asymmetry of the phase function.")
        .def_property_readonly("white_sky_albedo",
                               [](const firn::VolumeOptics &o) { return toTuple(firn::whiteSkyAlbedo(o)); },
                               "KZ04 spherical (white-sky) albedo of a deep layer per channel: how white it looks.")
        .def("sigma_t", &firn::sigmaT, py::arg("density"), "Extinction coefficient (1/m) at a density (kg/m^3).")
        .def(
            "transport_mean_free_path",
            [](const firn::VolumeOptics &o, double density) {
                return toTuple(firn::transportMeanFreePath(o, density));
            },
            py::arg("density"), "1 / (sigma_t (1 - omega g)) per channel (m) at a density (kg/m^3).")
        .def(
            "diffusion_length",
            [](const firn::VolumeOptics &o, double density) { return toTuple(firn::diffusionLength(o, density)); },
            py::arg("density"),
            "e-folding depth of diffuse light, 1 / sqrt(3 sigma_a sigma_tr), per channel (m) at a density (kg/m^3).")
        .def("__repr__", [](const firn::VolumeOptics &o) {
            std::ostringstream text;
            text.precision(9);
            text << "VolumeOptics(extinction_per_density=" << o.extinctionPerDensity << ", albedo=(" << o.albedo.r
                 << ", " << o.albedo.g << ", " << o.albedo.b << "), g=" << o.g << ")";
            return text.str();
        });
}

void bindSnowOptics(py::module_ &m) {
    m.attr("ICE_DENSITY") = firn::kIceDensity;
    m.attr("WATER_DENSITY") = firn::kWaterDensity;

    m.def(
        "optics",
        [](std::optional<double> r, std::optional<double> ssa, std::optional<double> density, double bc, double dust,
           double water, double B, double g) {
            return firn::snowOptics(snowFrom(r, ssa, density, bc, dust, water, B, g, true));
        },
        FIRN_SNOW_KWARGS,
        withSnowArgs(R"doc(
Snow optics after Kokhanovsky & Zege (2004) with Warren & Brandt (2008) ice: returns a VolumeOptics with
extinction per unit density, single-scattering albedo per linear Rec.709 channel (colour-matched over
390-800 nm so the snow's white-sky albedo has the colour of its spectrum) and g. See docs/optics.md.)doc")
            .c_str());

    m.def(
        "co_albedo",
        [](double wavelength, std::optional<double> r, std::optional<double> ssa, std::optional<double> density,
           double bc, double dust, double water, double B, double g) {
            return firn::coAlbedo(snowFrom(r, ssa, density, bc, dust, water, B, g, false), wavelength);
        },
        py::arg("wavelength"), FIRN_SNOW_KWARGS,
        withSnowArgs("Spectral 1 - omega of snow at a wavelength (m, 390-800 nm).").c_str());

    m.def(
        "kz04_spherical_albedo",
        [](double wavelength, std::optional<double> r, std::optional<double> ssa, std::optional<double> density,
           double bc, double dust, double water, double B, double g) {
            const firn::SnowParameters snow = snowFrom(r, ssa, density, bc, dust, water, B, g, false);
            return firn::kz04SphericalAlbedo(firn::coAlbedo(snow, wavelength), snow.g);
        },
        py::arg("wavelength"), FIRN_SNOW_KWARGS,
        withSnowArgs("KZ04 spherical (white-sky, diffuse light) albedo of deep snow at a wavelength (m).").c_str());

    m.def(
        "kz04_plane_albedo",
        [](double wavelength, double cosZenith, std::optional<double> r, std::optional<double> ssa,
           std::optional<double> density, double bc, double dust, double water, double B, double g) {
            const firn::SnowParameters snow = snowFrom(r, ssa, density, bc, dust, water, B, g, false);
            return firn::kz04PlaneAlbedo(firn::coAlbedo(snow, wavelength), snow.g, cosZenith);
        },
        py::arg("wavelength"), py::arg("cos_zenith"), FIRN_SNOW_KWARGS,
        withSnowArgs("KZ04 plane (black-sky) albedo of deep snow at a wavelength (m) for the sun at cos(zenith).")
            .c_str());

    m.def(
        "kz04_albedo",
        [](double wavelength, double cosZenith, double diffuseFraction, std::optional<double> r,
           std::optional<double> ssa, std::optional<double> density, double bc, double dust, double water, double B,
           double g) {
            const firn::SnowParameters snow = snowFrom(r, ssa, density, bc, dust, water, B, g, false);
            return firn::kz04Albedo(firn::coAlbedo(snow, wavelength), snow.g, cosZenith, diffuseFraction);
        },
        py::arg("wavelength"), py::arg("cos_zenith"), py::arg("diffuse_fraction"), FIRN_SNOW_KWARGS,
        withSnowArgs(R"doc(
KZ04 albedo of deep snow at a wavelength (m) under a mixed sky: (1 - f) plane(cos_zenith) + f spherical, with
f = diffuse_fraction of the irradiance.)doc")
            .c_str());

    m.def("grain_radius_from_ssa", &firn::grainRadiusFromSsa, py::arg("ssa"),
          "Optical grain radius (m) from specific surface area (m^2/kg): 3 / (917 SSA).");
}

void bindTables(py::module_ &m) {
    m.def(
        "ice_refractive_index",
        [](double wavelength) {
            const firn::ComplexIndex index = firn::iceRefractiveIndex(wavelength);
            return py::make_tuple(index.n, index.kappa);
        },
        py::arg("wavelength"), "(n, kappa) of ice at a wavelength (m, 390-800 nm), Warren & Brandt (2008).");
    m.def("ice_absorption", &firn::iceAbsorption, py::arg("wavelength"),
          "Absorption coefficient of ice, 4 pi kappa / lambda (1/m), at a wavelength (m, 390-800 nm).");
    m.def("water_absorption", &firn::waterAbsorption, py::arg("wavelength"),
          "Absorption coefficient of liquid water (1/m) at a wavelength (m, 390-800 nm): Pope & Fry (1997), "
          "Smith & Baker (1981) above 700 nm.");
    m.def(
        "spectral_grid",
        [] {
            std::vector<double> wavelengths;
            for (std::size_t i = 0; i < firn::kSpectrumSamples; ++i)
                wavelengths.push_back(firn::spectrumWavelengthNm(i) * 1e-9);
            return wavelengths;
        },
        "The wavelengths (m) Firn's optics integrate over: 390-800 nm in 10 nm steps.");
    m.def(
        "reflectance_to_rgb",
        [](const std::vector<double> &values) {
            if (values.size() != firn::kSpectrumSamples)
                throw firn::InvalidArgument("reflectance_to_rgb needs one value per spectral_grid() wavelength (" +
                                            std::to_string(firn::kSpectrumSamples) + "), got " +
                                            std::to_string(values.size()));
            firn::Spectrum spectrum{};
            std::copy(values.begin(), values.end(), spectrum.begin());
            return toTuple(firn::reflectanceToRgb(spectrum));
        },
        py::arg("values"),
        "Linear Rec.709 RGB of a reflectance sampled on spectral_grid() (CIE 1931 observer, D65 light; a flat "
        "spectrum gives equal RGB).");
}

}  // namespace

void bindOptics(py::module_ &m) {
    bindVolumeOptics(m);
    bindSnowOptics(m);
    bindTables(m);
}

}  // namespace firncore
