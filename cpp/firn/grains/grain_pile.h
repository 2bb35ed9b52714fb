#pragma once

// A deep pile of ice grains in a box, for measuring what a packing of spheres does to light: the albedo the
// volumetric optics (Kokhanovsky & Zege 2004) must predict. The box (floor at z = 0, side `width`) has mirror
// walls: a path that reaches one continues as in the mirrored pile, so the measured pile behaves as an
// infinitely wide one with no edge losses; grains are accumulated into it from above.
#include <cstddef>
#include <cstdint>

#include "firn/geometry/mesh.h"
#include "firn/grains/accumulation.h"
#include "firn/grains/grain_set.h"
#include "firn/grains/grain_tracer.h"
#include "firn/util/color.h"
#include "firn/util/progress.h"

namespace firn {

struct PileSettings {
    double radius = 1e-3;          // m
    double radiusVariation = 0.0;  // sigma, as in AccumulationSettings
    double width = 30e-3;          // m, side of the square box
    double depth = 0.1;            // m, wanted depth of grains (the count assumes a volume fraction of 0.25)
    std::uint64_t seed = 0;
};

struct GrainPile {
    TriangleMesh box;               // floor (triangles 0, 1) and four walls (2..9)
    AccumulationResult accumulation;
    double width = 0.0;             // m
    double top = 0.0;               // m, height of the highest grain's top
};

// InvalidArgument for non-positive sizes; BudgetExceeded through accumulation for piles of too many grains.
GrainPile buildGrainPile(const PileSettings &settings, Progress *progress = nullptr);

// Ice volume fraction (m^3/m^3) of the pile's interior, away from its walls, floor and rough top: grains whose
// centre lies within the central box [margin, width - margin]^2 x [zLow, zHigh], by their whole volume
// (the region is many grains wide, so grains cut by its faces average out).
double pileVolumeFraction(const GrainPile &pile, double margin, double zLow, double zHigh);

struct PileAlbedo {
    Rgb mean{0.0};           // plane albedo for a collimated beam at normal incidence (mu0 = 1)
    Rgb standardError{0.0};
    GrainPathStats stats;
};

// How the pile is lit: a collimated beam straight down (the plane albedo at mu0 = 1) or a uniform sky (the
// spherical, white-sky albedo: directions cosine-weighted over the upper hemisphere).
enum class PileLight { Collimated, Diffuse };

// The albedo: paths enter at uniform points of the central half of the box's top and the power that leaves
// upward is counted (a white sky of radiance 1 seen by each path: its escape weight).
PileAlbedo measurePileAlbedo(const GrainPile &pile, double eta, const Rgb &iceAbsorption, const Rgb &groundAlbedo,
                             std::size_t paths, std::uint64_t seed, Progress *progress = nullptr,
                             PileLight light = PileLight::Collimated);

}  // namespace firn
