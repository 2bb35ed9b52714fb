// Grain snow from Python: Chrisman's accumulation of ice spheres, the brute-force grain renderer and the pile
// albedo that validates the volumetric optics.
#include <array>
#include <cmath>
#include <optional>
#include <string>

#include <glm/geometric.hpp>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "firn/grains/accumulation.h"
#include "firn/grains/grain_pile.h"
#include "firn/grains/grain_tracer.h"
#include "firn/grains/sphere_optics.h"
#include "firn/optics/snow_optics.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"
#include "mesh_arrays.h"

namespace py = pybind11;

namespace firncore {

namespace {

using Triple = RgbTuple;
using Doubles = DoubleArray;

glm::dvec3 vec(const Triple &t) { return rgb(t); }

std::vector<glm::dvec3> rowsFrom(const py::handle &values, const char *what) {
    const Doubles a = py::cast<Doubles>(values);
    if (a.ndim() != 2 || a.shape(1) != 3) throw firn::InvalidArgument(std::string(what) + " must be an (N, 3) array");
    std::vector<glm::dvec3> out(a.shape(0));
    for (py::ssize_t i = 0; i < a.shape(0); ++i) out[i] = {a.at(i, 0), a.at(i, 1), a.at(i, 2)};
    return out;
}

firn::GrainSet grainsFrom(const py::handle &centres, const py::handle &radii) {
    firn::GrainSet grains;
    grains.centres = rowsFrom(centres, "grain centres");
    const Doubles r = py::cast<Doubles>(radii);
    if (r.ndim() != 1) throw firn::InvalidArgument("grain radii must be a 1-D array (m)");
    grains.radii.assign(r.data(), r.data() + r.size());
    firn::validate(grains);
    return grains;
}

py::dict statsOf(const firn::AccumulationResult &r) {
    py::dict d;
    d["rays"] = r.rays, d["missed"] = r.missed, d["steep"] = r.steep, d["overlapping"] = r.overlapping;
    return d;
}

}  // namespace

void bindGrains(py::module_ &m) {
    m.attr("GRAIN_OVERLAP_TOLERANCE") = firn::kGrainOverlapTolerance;

    m.def(
        "accumulate_grains",
        [](const py::object &vertices, const py::object &triangles, std::size_t count, double radius,
           double radiusVariation, const Triple &direction, double maxSlopeDeg, std::uint64_t seed,
           std::size_t maxRays, std::shared_ptr<firn::Progress> progress) {
            const firn::TriangleMesh mesh = meshFromArrays(vertices, triangles, "scene");
            firn::AccumulationSettings s;
            s.count = count, s.radius = radius, s.radiusVariation = radiusVariation, s.direction = vec(direction);
            s.maxSlope = maxSlopeDeg * firn::kPi / 180.0, s.seed = seed, s.maxRays = maxRays;
            firn::validate(s);
            const firn::AccumulationResult result = longCall([&] { return firn::accumulateGrains(mesh, s, progress.get()); });
            Doubles radii(py::ssize_t(result.grains.size()));
            std::copy(result.grains.radii.begin(), result.grains.radii.end(), radii.mutable_data());
            return py::make_tuple(rgbRows(result.grains.centres), radii, statsOf(result));
        },
        py::arg("vertices"), py::arg("triangles"), py::arg("count"), py::arg("radius"), py::arg("radius_variation") = 0.0,
        py::arg("direction") = Triple{0.0, 0.0, -1.0}, py::arg("max_slope_deg") = 60.0, py::arg("seed") = 0,
        py::arg("max_rays") = 0, py::arg("progress") = nullptr, R"doc(
Chrisman's accumulation: `count` ice grains of radius `radius` (m) times (1 + radius_variation u), u uniform in
[-1, 1], fall along `direction` onto the triangles ((N, 3) vertices in m, (M, 3) indices) and onto each other;
surfaces steeper than max_slope_deg are skipped; a grain that would press into another grain or a triangle by
more than GRAIN_OVERLAP_TOLERANCE of its radius is discarded. Deterministic for a seed. Stops after max_rays rays
(0: 20 count + 10000) with fewer grains. Returns (centres (N, 3) m, radii (N,) m, stats dict: rays, missed,
steep, overlapping).)doc");

    m.def(
        "grain_radiance",
        [](const py::object &centres, const py::object &radii, const py::object &origins, const py::object &directions,
           const py::object &vertices, const py::object &triangles, const py::object &surfaceAlbedo, double eta,
           const std::optional<Triple> &iceAbsorption, const Triple &sky, const std::optional<Triple> &sunDirection,
           double sunAngularRadius, const Triple &sunRadiance, int samples, std::uint64_t seed,
           std::shared_ptr<firn::Progress> progress) {
            if (samples < 1 || samples > 1000000) throw firn::InvalidArgument("samples must be between 1 and 1e6");
            const firn::GrainSet grains = grainsFrom(centres, radii);
            const firn::TriangleMesh mesh = vertices.is_none() ? firn::TriangleMesh{}
                                                               : meshFromArrays(vertices, triangles, "scene");
            firn::GrainMaterials materials;
            materials.eta = eta;
            double meanRadius = 0.0;
            for (double r : grains.radii) meanRadius += r / double(std::max<std::size_t>(1, grains.size()));
            materials.iceAbsorption = iceAbsorption ? vec(*iceAbsorption)
                                                    : (grains.empty() ? firn::Rgb(0.0) : firn::iceAbsorptionRgb(meanRadius));
            for (const glm::dvec3 &a : rowsFrom(py::cast<Doubles>(surfaceAlbedo).reshape({-1, 3}), "surface albedo"))
                materials.surfaces.push_back(firn::GrainSurface{a, false});
            materials.skyRadiance = vec(sky);
            if (sunDirection) materials.sun = firn::GrainSun{vec(*sunDirection), sunAngularRadius, vec(sunRadiance)};
            const std::vector<glm::dvec3> o = rowsFrom(origins, "origins"), d = rowsFrom(directions, "directions");
            if (o.size() != d.size()) throw firn::InvalidArgument("origins and directions differ in length");
            std::vector<firn::GrainRay> rays(o.size());
            for (std::size_t i = 0; i < o.size(); ++i) rays[i] = {o[i], d[i]};
            std::vector<firn::GrainRadiance> estimates = longCall([&] {
                const firn::GrainTracer tracer(mesh, grains, materials);
                return tracer.radiance(rays, samples, seed, progress.get());
            });
            std::vector<glm::dvec3> mean, error;
            for (const auto &e : estimates) mean.push_back(e.mean), error.push_back(e.standardError);
            return py::make_tuple(rgbRows(mean), rgbRows(error));
        },
        py::arg("centres"), py::arg("radii"), py::arg("origins"), py::arg("directions"), py::arg("vertices") = py::none(),
        py::arg("triangles") = py::none(), py::arg("surface_albedo") = Triple{0.8, 0.8, 0.8},
        py::arg("eta") = firn::kIceRefractiveIndex, py::arg("ice_absorption") = py::none(),
        py::arg("sky") = Triple{1.0, 1.0, 1.0}, py::arg("sun_direction") = py::none(), py::arg("sun_angular_radius") = 0.05,
        py::arg("sun_radiance") = Triple{0.0, 0.0, 0.0}, py::arg("samples") = 16, py::arg("seed") = 0,
        py::arg("progress") = nullptr, R"doc(
Brute-force Monte Carlo over ice spheres (centres (N, 3) m, radii (N,) m) and diffuse triangles (vertices,
triangles; surface_albedo one RGB for all or (M, 3) per triangle: then no triangle may be degenerate, as the
core drops those): Fresnel reflect/refract at each interface,
absorption inside the ice (ice_absorption RGB 1/m; None: Warren & Brandt 2008 in Rec.709 channels at the mean
radius), a uniform sky (W/m^2/sr) and optionally a sun disc (direction toward it, angular radius rad, radiance
W/m^2/sr) that escaping paths can hit. Radiance along camera rays (origins, directions (N, 3)). Returns (mean,
standard error), each (N, 3) W/m^2/sr.)doc");

    m.def(
        "grain_pile_albedo",
        [](double radius, double width, double depth, double radiusVariation, double eta,
           const std::optional<Triple> &iceAbsorption, const Triple &groundAlbedo, std::size_t paths,
           std::uint64_t seed, const std::string &illumination, std::shared_ptr<firn::Progress> progress) {
            if (illumination != "COLLIMATED" && illumination != "DIFFUSE")
                throw firn::InvalidArgument("illumination must be 'COLLIMATED' or 'DIFFUSE', not '" + illumination + "'");
            const bool diffuse = illumination == "DIFFUSE";
            firn::PileSettings s;
            s.radius = radius, s.width = width, s.depth = depth, s.radiusVariation = radiusVariation, s.seed = seed;
            if (paths < 1 || paths > 100'000'000) throw firn::InvalidArgument("paths must be between 1 and 1e8");
            const firn::Rgb gamma = iceAbsorption ? vec(*iceAbsorption) : firn::iceAbsorptionRgb(radius);
            py::dict out;
            firn::GrainPile pile;
            firn::PileAlbedo albedo;
            double f = 0.0;
            firn::Rgb predicted;
            longCall([&] {
                pile = firn::buildGrainPile(s, progress.get());
                const double margin = 2.0 * radius * (1.0 + radiusVariation);
                f = firn::pileVolumeFraction(pile, margin, 0.2 * pile.top, 0.7 * pile.top);
                albedo = firn::measurePileAlbedo(pile, eta, gamma, vec(groundAlbedo), paths, seed, progress.get(),
                                                 diffuse ? firn::PileLight::Diffuse : firn::PileLight::Collimated);
                predicted = firn::kz04SpherePileAlbedo(eta, gamma, radius, diffuse);
            });
            out["albedo"] = Triple{albedo.mean.x, albedo.mean.y, albedo.mean.z};
            out["standard_error"] = Triple{albedo.standardError.x, albedo.standardError.y, albedo.standardError.z};
            out["kz04_albedo"] = Triple{predicted.x, predicted.y, predicted.z};
            out["ice_absorption"] = Triple{gamma.x, gamma.y, gamma.z};
            out["volume_fraction"] = f;
            out["density"] = f * firn::kIceDensity;
            out["grains"] = pile.accumulation.grains.size();
            out["top"] = pile.top;
            out["accumulation"] = statsOf(pile.accumulation);
            out["mean_events"] = albedo.stats.meanEvents;
            out["bailed_out"] = albedo.stats.bailedOut;
            return out;
        },
        py::arg("radius"), py::arg("width"), py::arg("depth"), py::arg("radius_variation") = 0.0,
        py::arg("eta") = firn::kIceRefractiveIndex, py::arg("ice_absorption") = py::none(),
        py::arg("ground_albedo") = Triple{0.0, 0.0, 0.0}, py::arg("paths") = 10000, py::arg("seed") = 0,
        py::arg("illumination") = "COLLIMATED", py::arg("progress") = nullptr, R"doc(
Accumulates a pile of grains (radius m, about `depth` m deep) in a mirror-walled box of side `width` (m) on a
ground of ground_albedo, and measures its albedo with `paths` paths: illumination 'COLLIMATED', the plane albedo
for a beam straight down (mu0 = 1), or 'DIFFUSE', the spherical (white-sky) albedo under a uniform sky. Returns a
dict: albedo and standard_error (RGB), kz04_albedo (KZ04's asymptotic albedo for the same light, from the
spheres' ray optics), ice_absorption (1/m), volume_fraction and density (917 f kg/m^3) of the pile's interior,
grains, top (m), accumulation stats, mean_events per path, bailed_out.)doc");

    m.def(
        "grain_sphere_optics",
        [](double radius, double absorption, double eta) {
            const firn::SphereRayOptics o = firn::sphereRayOptics(eta, absorption, radius);
            return py::make_tuple(o.absorptionEfficiency, o.g);
        },
        py::arg("radius"), py::arg("absorption"), py::arg("eta") = firn::kIceRefractiveIndex, R"doc(
Ray optics of one ice sphere (radius m, absorption 1/m): (Q_abs, g) without diffraction.)doc");

    m.def(
        "ice_absorption_rgb", [](double radius) { return tuple(firn::iceAbsorptionRgb(radius)); },
        py::arg("radius"), R"doc(
Absorption coefficient of ice (1/m) per Rec.709 channel, for grains of `radius` (m): Warren & Brandt 2008 made RGB
the way the rest of the core makes it (what the grain tracer uses by default, and the ice material of Add Grain
Snow).)doc");
}

}  // namespace firncore
