// Snow's small-scale structure from Python: the constants the snow material's sub-ball and glint patterns need,
// and what those patterns add up to (the oracles of the add-on's render tests).
#include <pybind11/stl.h>

#include "bindings.h"
#include "firn/structure/cell_balls.h"
#include "firn/structure/glints.h"
#include "firn/structure/sub_balls.h"

namespace py = pybind11;

namespace firncore {

void bindStructure(py::module_ &m) {
    py::class_<firn::SubBallPattern>(m, "SubBallPattern", "Sub-balls as the snow material draws them.")
        .def_readonly("cell_size", &firn::SubBallPattern::cellSize, "m: one grain per lattice cell of this edge")
        .def_property_readonly("radius", [](const firn::SubBallPattern &p) { return p.balls.radius; }, "cells")
        .def_property_readonly("variation", [](const firn::SubBallPattern &p) { return p.balls.variation; })
        .def_readonly("mean_kernel", &firn::SubBallPattern::meanKernel, "mean over space of (1 - (d/R)^2)^3")
        .def_readonly("fade_start", &firn::SubBallPattern::fadeStart, "m below the surface")
        .def_readonly("fade_end", &firn::SubBallPattern::fadeEnd, "m below the surface")
        .def_readonly("strength", &firn::SubBallPattern::strength)
        .def("density_factor", &firn::SubBallPattern::densityFactor, py::arg("distance"), py::arg("radius"),
             py::arg("depth"), "Density factor at `distance` cells from a grain of `radius` cells, `depth` m down.");

    m.def(
        "sub_ball_pattern",
        [](double radius, double variation, double depth, double strength, double sigmaT) {
            firn::SubBallSettings s;
            s.radius = radius, s.variation = variation, s.depth = depth, s.strength = strength;
            return firn::subBallPattern(s, sigmaT);
        },
        py::arg("radius"), py::arg("variation"), py::arg("depth"), py::arg("strength"), py::arg("sigma_t"), R"doc(
Nishita's sub-balls for grains of `radius` (m) times (1 + variation (2u - 1)), fading out `depth` optical depths
below the surface of snow of extinction `sigma_t` (1/m); `strength` 0..1. ValueError on bad input.)doc");

    py::class_<firn::GlintFacets>(m, "GlintFacets", "Glint facets as the snow material draws them.")
        .def_readonly("cell_size", &firn::GlintFacets::cellSize, "m")
        .def_property_readonly("radius", [](const firn::GlintFacets &f) { return f.balls.radius; }, "cells")
        .def_readonly("coverage", &firn::GlintFacets::coverage, "fraction of the surface inside a facet");

    m.def(
        "glint_facets",
        [](double facetsPerSquareMetre, double facetRadius) {
            return firn::glintFacets({facetsPerSquareMetre, facetRadius});
        },
        py::arg("facets_per_m2"), py::arg("facet_radius"),
        "Facets the surface cuts per m^2 and their radius (m); ValueError beyond 1 / (4 R^2) per m^2.");
    m.def("mean_glint_radiance", &firn::meanGlintRadiance, py::arg("coverage"), py::arg("eta"), py::arg("cos_half"),
          "Mean radiance the facets add per unit sun irradiance (W/m^2/sr per W/m^2).");
    m.def("glint_fraction", &firn::glintFraction, py::arg("coverage"), py::arg("sun_solid_angle"), py::arg("cos_half"),
          "Fraction of the surface that mirrors a small sun (solid angle in sr) to the viewer.");
    m.def(
        "cell_ball_means",
        [](double radius, double variation, std::uint64_t samples, std::uint64_t seed) {
            const firn::CellBallMeans means = firn::cellBallMeans({radius, variation}, samples, seed);
            return py::make_tuple(means.coverage, means.kernel);
        },
        py::arg("radius"), py::arg("variation") = 0.0, py::arg("samples") = 200000, py::arg("seed") = 0,
        "(coverage, mean kernel) of one ball per unit cell of radius `radius` cells (Cycles' Voronoi, randomness 1).");
}

}  // namespace firncore
