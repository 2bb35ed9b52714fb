#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "firn/transport/scene.h"

namespace firn {

// An exact pre-test before beamAt's sun shadow rays (RayCaster::occluded towards points of the sun's disc): whether
// no occluder triangle can lie on any of them. Heights are measured along the sun's direction, positions across it
// on a grid of voxel-wide cells over the medium; each cell lists the triangles near it. A ray from p rises in height
// as it goes and drifts across at most tan(the disc's radius) per metre risen, so a triangle is cleared when it lies
// wholly below p, or farther across than the drift reaches before its top, or when its plane under p lies below p and
// rises across slower than the rays drift. Each test is padded by linkPad (far past the rays' float rounding and
// Embree's): a cleared point's rays have no hit. On the car each lit voxel cast four such rays (sunSamples), about
// half the light phase's Embree queries, nearly all of them through open air above the car's skin
// (docs/benchmarks.md, car-light).
class SunClearance {
  public:
    // Built for points near the medium; none (clear() always false) without occluders, or for a disc so wide that
    // the drift spans many cells.
    SunClearance(const Medium &medium, const Occluders &occluders, const SunLight &sun);

    // True only where beamAt's shadow rays from `point` (m) towards any direction within the sun's disc meet no
    // occluder; false where one may.
    bool clear(const glm::dvec3 &point) const;

  private:
    struct Across {  // a triangle as the sun sees it: (a, b) across the sun's direction, height up it (m)
        glm::dvec2 lo, hi;                 // its corners' box across
        std::array<glm::dvec2, 3> normal;  // unit, each edge's outward direction across (zero on a point's edge)
        std::array<double, 3> extent;      // the triangle's furthest reach along each `normal`
        double top = 0.0;                  // its highest corner's height
        glm::dvec2 corner;                 // its first corner across, and its plane's height there and slope across
        double height = 0.0;
        glm::dvec2 slope{0.0};
        bool planar = false;  // not seen edge-on: the plane's slope is finite (and below kSteepest / drift)
    };
    bool cleared(const Across &t, const glm::dvec2 &p, double height) const;
    // The cell holding `p` across, or -1 outside the grid.
    std::int64_t cellOf(const glm::dvec2 &p) const;

    glm::dvec3 up_{0.0}, u_{0.0}, v_{0.0};  // unit: towards the sun, and two directions across
    double drift_ = 0.0;                     // m across per m of height, at most, along a ray within the disc
    double pad_ = 0.0;                       // m
    double lowest_ = 0.0, highest_ = 0.0;    // m: the heights a query may start from (lowest_) and the triangles' top
    double reach_ = 0.0;                     // m across: how far beyond a cell its list holds the triangles
    glm::dvec2 origin_{0.0};                 // m: the grid's corner across
    double cell_ = 0.0;                      // m
    int columns_ = 0, rows_ = 0;             // none: no pre-test
    std::vector<Across> triangles_;
    std::vector<std::uint32_t> start_, listed_;  // per cell, its triangles' indices in triangles_ (CSR)
};

// Scene::sunClearance for the bake: one per sun where there are occluders, none otherwise.
std::vector<std::shared_ptr<const SunClearance>> sunClearances(const Scene &scene);

}  // namespace firn
