#pragma once

// Nishita et al. (1997)'s sub-balls: snow grains as tiny metaballs in the shallow region under the surface,
// drawn from a solid texture repeated through space (cell_balls.h) that the snow material evaluates at every
// shading point, far below the voxel size. They modulate the density with mean 1 at every depth, so the snow
// keeps its mass, and a bake, which stores light per unit extinction, still applies.
#include "firn/structure/cell_balls.h"

namespace firn {

struct SubBallSettings {
    double radius = 0.5e-3;  // m, the grains' mean radius
    double variation = 0.3;  // grain radius r (1 + variation (2u - 1)), u uniform
    double depth = 3.0;      // optical depths below the surface where the grains fade out
    double strength = 1.0;   // 0: smooth snow, 1: all the shallow snow's mass in the grains

    void validate() const;
};

// What the material needs: density factor 1 + strength w(depth) (K / meanKernel - 1), where K is the nearest
// ball's Wyvill kernel (1 - (d/R)^2)^3 and w is 1 above fadeStart, 0 below fadeEnd, linear between.
struct SubBallPattern {
    double cellSize = 0.0;   // m: one grain per cell of this edge
    CellBalls balls;         // in cells
    double meanKernel = 0.0; // mean of K over space
    double fadeStart = 0.0;  // m below the surface
    double fadeEnd = 0.0;    // m below the surface
    double strength = 0.0;

    // The density factor at `distance` (cells) from the nearest centre, whose ball has radius `radius` (cells),
    // `depth` m below the surface.
    double densityFactor(double distance, double radius, double depth) const;
};

// The pattern of grains of the settings in snow of extinction sigmaT (1/m) near its surface (the depth in
// optical depths becomes metres at that sigmaT).
SubBallPattern subBallPattern(const SubBallSettings &settings, double sigmaT);

}  // namespace firn
