#pragma once

#include <array>
#include <functional>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/monte_carlo.h"
#include "firn/util/random.h"

namespace firn {

// Points about a voxel drawn where cameras see its stored source (docs/bake.md, Method 3). The renderer reads the
// source grids trilinearly, so a voxel's lobes light every point within a voxel of its centre, weighted by the
// trilinear hat; and in a voxel of many optical depths a camera ray sees the first optical depth from its side,
// most of it in the density's ramp before the voxel's own cube (at sigma_t h 20, tau 2.5 from the air
// neighbour's centre to the face). What cameras see of the lobes from all of `directions` together weighs a point
// x by hat(x) sigma_t(x) sum_j exp(-tau(x -> the snow's bounds along w_j), up to 10): the points gathering the
// voxel's source are drawn so (spray_dense 21.7 -> 19.1 % over 4 seeds; converged, 4096 paths per voxel, 18.9 ->
// 14.5 %).
//
// Candidates are drawn for each of the directions, as many as its visibility (visibilityFrom) times
// the hat's box's projected area along it: entering the box through the faces that face w, by projected area
// and the hat's tent across each face, and flying along -w to a collision drawn given one within the box (the
// trilinear density's optical depth, midpoint rule on half-voxel steps, inverted), each weighted by the weight
// above over the candidates' density (their mixture's: the balance heuristic). kVisibleCandidates per point,
// then resampled in proportion to their weights (stratified), so that the points gather with equal weight (drawn
// directly, with a quarter of them spread evenly over the voxel, the weights' effective sample size was 0.26-0.39
// and the estimates' noise swamped the gain: spray_dense 23.8-25.1 %).
constexpr int kVisibleCandidates = 2;  // 4: 19.8 %, the trace 3.3 -> 5.8 processor s (2 at quarter-voxel steps: 18.8 %, 4.7 s)

class VisiblePoints {
  public:
    // `candidates`: how many will be drawn (candidate i by draw(i, ...)).
    VisiblePoints(const Medium &medium, const openvdb::Coord &voxel, const SourceDirections &directions, int candidates);

    struct Candidate {
        glm::dvec3 p{0.0};    // m, world space
        double weight = 0.0;  // what cameras see of p over the candidates' density
    };
    // Candidate i from u in [0, 1)^3.
    Candidate draw(int i, const std::array<double, 3> &u);

    // The density lookups and column steps taken so far (the visibility included): the draws' work in tracking
    // steps, which the bake's budget counts (SourceEstimate::steps, planGathering).
    long steps() const { return lookups_ + marcher_.columnSteps(); }

  private:
    // Optical depth from y (index space about the voxel's centre) along d (unit) to where it leaves the hat's box.
    double depthOut(const glm::dvec3 &y, const glm::dvec3 &d);
    double sigmaT(const glm::dvec3 &y);  // 1/m

    const Medium &medium_;
    Medium::ColumnMarcher marcher_;
    glm::dvec3 centre_;  // index space
    const SourceDirections &directions_;
    std::array<double, kSourceDirections> projectedArea_{};  // voxels^2, of the hat's box along each direction
    std::array<int, kSourceDirections> count_{};             // candidates drawn for each direction
    std::vector<int> drawnFor_;                              // per candidate, its direction
    // Per direction, the earlier one exactly opposite it (-1: none): the depth out along one is the depth back
    // along the other (the 26 neighbour directions pair up), walked once per candidate.
    std::array<int, kSourceDirections> opposite_{};
    long lookups_ = 0;                                       // sigmaT's
};

// `samples` points of `voxel` drawn where cameras see it (VisiblePoints), m, world space, the candidates from
// `next` (points of [0, 1)^3) and resampled with `rng`; none where no candidate is seen. Adds their work to
// `steps` (VisiblePoints::steps).
std::vector<glm::dvec3> visiblePoints(const Medium &medium, const openvdb::Coord &voxel,
                                      const SourceDirections &directions, int samples,
                                      const std::function<std::array<double, 3>()> &next, Rng &rng, long &steps);

// A point where a camera looking at a voxel's air face collides (facePoints), with the voxel's share of the
// trilinear hat there along the face's axis (1 at its centre, 0 at the air neighbour's): what of that collision
// the render reads from the voxel's own value, the rest from the air neighbour's (MonteCarloReference::faceSourceIn).
struct FacePoint {
    glm::dvec3 p;                     // m, world space
    double voxelShare = 0.0;
    double depth = 0.0, chord = 0.0;  // optical depth along the normal to p, and over the two voxels
};

// `samples` points of `voxel` where a camera looking straight at its air face `face` (0..5: -x, +x, -y, +y, -z,
// +z) sees it (docs/bake.md, Method 3: a floating layer one voxel thick is seen from each side in that side's
// first optical depth): across the face (uniform), at a collision along the face's inward normal from the
// neighbour's centre through the voxel (the trilinear density's optical depth, midpoint rule, inverted; given one
// within those two voxels) at the depth a camera ray sees it from directions cosine-weighted about the normal
// (stratified; its lateral travel left out: along the normal alone, the 16 x 16 x 1 layer at sigma_t h 15 read
// 9.7 % from above, 20.4 % from below, against 9.1, 19.2 %; branch float-voxel), from `next`'s points of
// [0, 1)^3. Adds the density lookups to `steps`.
std::vector<FacePoint> facePoints(const Medium &medium, const openvdb::Coord &voxel, int face, int samples,
                                  const std::function<std::array<double, 3>()> &next, long &steps);

}  // namespace firn
