#pragma once

// A solid texture of balls repeated through space with no memory: one ball per unit lattice cell, its centre
// uniform in the cell and its radius R (1 + v (2u - 1)) with u uniform per cell. It is what Cycles' Voronoi
// texture draws (3-D, Euclidean F1, randomness 1; the cell's Color gives u), so a shader can place the balls and
// the core can say what they add up to. Lengths are in cells. A point belongs to its nearest centre's ball only
// (F1), so where two balls overlap the nearer centre wins.
#include <cstdint>

namespace firn {

struct CellBalls {
    double radius = 0.25;   // R, cells (at most 1: Cycles searches the 27 neighbouring cells)
    double variation = 0.0; // v in [0, 1)

    // Throws InvalidArgument naming the setting out of range.
    void validate() const;
};

// Means over space of the pattern.
struct CellBallMeans {
    double coverage = 0.0;  // fraction of space inside a ball (of a plane cut anywhere: the centres are uniform)
    double kernel = 0.0;    // of Wyvill's degree-6 kernel (1 - (d/R)^2)^3 of the nearest ball, 0 outside it
};

// The means by Monte Carlo over `samples` independent lattices (the overlaps of neighbouring balls have no
// closed form); deterministic for a seed. Without overlaps they are 4/3 pi R^3 (1 + v^2) and
// 64 pi / 315 R^3 (1 + v^2): see cellBallMeansWithoutOverlap.
CellBallMeans cellBallMeans(const CellBalls &balls, std::uint64_t samples = 200000, std::uint64_t seed = 0);

// The same means when no two balls overlap: exact, and the limit of cellBallMeans for small R.
CellBallMeans cellBallMeansWithoutOverlap(const CellBalls &balls);

}  // namespace firn
