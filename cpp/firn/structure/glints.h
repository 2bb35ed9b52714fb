#pragma once

// Glints: small randomly oriented mirror facets of ice at the snow's surface (Nishita et al. 1997's prisms; the
// discrete facets of Jakob et al. 2014), from a solid texture (cell_balls.h): where the surface cuts a cell's
// ball there is a facet, facing a direction uniform over the sphere drawn from the cell. Only facets whose
// normal halves the view and the sun reflect the sun: sparse, bright points that move with camera and sun.
#include "firn/structure/cell_balls.h"

namespace firn {

struct GlintSettings {
    double facetsPerSquareMetre = 5e7;  // facets the surface cuts, per m^2 of surface
    double facetRadius = 0.05e-3;       // m

    void validate() const;
};

struct GlintFacets {
    double cellSize = 0.0;  // m
    CellBalls balls;        // in cells
    double coverage = 0.0;  // fraction of the surface inside a facet
};

// A plane cuts a ball of radius R in a lattice of cell c when its centre is within R of it: 2 R / c^3 facets per
// m^2, so c = (2 R / n)^(1/3). Balls must fit their cells (R <= c / 2): at most 1 / (4 R^2) facets per m^2.
GlintFacets glintFacets(const GlintSettings &settings);

// Mean radiance the facets add to the surface per unit sun irradiance (W/m^2/sr per W/m^2), seen from a direction
// whose half vector with the sun makes angle theta_d with the view: a F(theta_d) / (8 pi cos theta_d), whatever
// the sun's size. (Facet normals uniform over the hemisphere facing the viewer, density 1/(2 pi) per sr; the
// normals reflecting a sun of solid angle Omega to the viewer span Omega / (4 cos theta_d), each reflecting
// F E / Omega.) eta: ice's refractive index.
double meanGlintRadiance(double coverage, double eta, double cosHalfAngle);

// Fraction of the surface that mirrors the sun (solid angle sunSolidAngle, sr) to the viewer:
// a Omega / (8 pi cos theta_d), for a sun small enough that cos theta_d is constant over it.
double glintFraction(double coverage, double sunSolidAngle, double cosHalfAngle);

}  // namespace firn
