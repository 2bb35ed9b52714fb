#pragma once

#include <cmath>

namespace firn {

// Snow density against depth below the snow surface. Overburden compacts snow, so density rises from
// its surface value towards a deeper value with an e-folding depth (an exponential approach, the shape of
// measured seasonal-snow and firn profiles, e.g. Herron & Langway 1980 in its first stage).
struct CompactionProfile {
    double densityTop = 120.0;     // kg/m^3 at the surface (fresh snow 50-150)
    double densityBottom = 350.0;  // kg/m^3 approached at depth (settled snow 200-400)
    double compaction = 0.5;       // 0: uniform densityTop; 1: densityBottom right below the surface
    double depth = 0.1;            // m, the layer's full depth: the e-folding depth scales with it

    // kg/m^3 at `z` m below the surface.
    double density(double z) const {
        if (compaction <= 0.0) return densityTop;
        if (compaction >= 1.0) return densityBottom;
        const double eFolding = 0.5 * depth * (1.0 - compaction) / compaction;  // m
        return densityTop + (densityBottom - densityTop) * (1.0 - std::exp(-std::max(z, 0.0) / eFolding));
    }
};

}  // namespace firn
