#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"
#include "firn/geometry/ray_caster.h"
#include "firn/util/progress.h"

namespace firn {

// Where falling snow lands (after Nishita 1997 and Chrisman): on target surfaces that face up, are not
// steeper than snow can hold, and can be reached by snow falling from a cone of directions.
struct SnowfallSettings {
    glm::vec3 direction{0.0f, 0.0f, -1.0f};  // the way snow falls (unit); tilting it models wind
    double spread = 0.26;                    // rad, half-angle of the cone snow falls from
    double maxSlope = 1.047;                 // rad from horizontal; steeper surfaces stay bare
    double spacing = 0.05;                   // m, mean distance between landing sites
    int exposureRays = 16;                   // rays per site into the cone (1 when spread is 0)
    std::uint64_t seed = 0;
    double maxSites = 50e6;                  // landing sites allowed, checked before placing any
};

struct LandingSite {
    glm::vec3 position;  // m, on the target surface
    glm::vec3 normal;    // unit, the side snow lies on
    float cover;         // 0..1: fraction of the full depth that lands here (exposure x slope)
};

// Fraction of the full depth that a surface tilted `slope` rad from horizontal holds: cos(slope) for the
// projected snowfall, easing to zero over the last 15 degrees before maxSlope (snow slides off).
double slopeCover(double slope, double maxSlope);

// Fraction of `rays` directions into the snowfall cone that leave `origin` (just off a surface of unit normal
// `normal`, on its snow side) without meeting `occluders`: the directions a low-discrepancy pattern over the
// cone, shifted by (shiftU, shiftV) in [0, 1) (the caller's seeded draws).
double snowfallExposure(const glm::vec3 &origin, const glm::vec3 &normal, const RayCaster &occluders,
                        const SnowfallSettings &settings, double shiftU, double shiftV);

// Sites at a mean density of one per spacing^2 of surface (a Kronecker (R2) sequence per triangle, randomly
// shifted: stratified and seeded); each site's exposure is the unblocked fraction of exposureRays rays cast
// into the snowfall cone against `occluders` (which should include the targets themselves).
// `depthWeights` (empty, or one 0..1 per target vertex: a vertex group or attribute painted by the user) scales
// each site's cover by its weight interpolated over the triangle. Sites that get no snow (cover below 1 %) are
// left out. Throws BudgetExceeded, before placing any, when the expected number of sites exceeds maxSites;
// InvalidArgument for weights of the wrong count or outside 0..1.
std::vector<LandingSite> findLandingSites(const TriangleMesh &targets, const RayCaster &occluders,
                                          const SnowfallSettings &settings, const SubProgress &progress,
                                          const std::vector<float> &depthWeights = {});

}  // namespace firn
