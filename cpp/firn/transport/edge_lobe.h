#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "firn/transport/source_lobe.h"

namespace firn {

// One air face of a voxel on a sharp edge or corner (SurfacePatch::sharp) and the radiance leaving it,
// L(w) = e0 + e1 . w over w . normal > 0 (the surface model's linear form, W/m^2/sr).
struct FaceExit {
    glm::dvec3 normal{0.0, 0.0, 1.0};
    double e0 = 0.0;
    glm::dvec3 e1{0.0};
};

// One flat air face of a sharp edge voxel and the lobe the air across it carries (EdgeFaceLobes' lobe, one channel).
struct FaceLobe {
    glm::dvec3 normal{0.0, 0.0, 1.0};
    double l0 = 0.0;
    glm::dvec3 l1{0.0};
};

// The two or three flat faces of an edge or corner (lobeBeyondFaces'), held in place: the air beside an edge asks for
// them on every read of its value.
struct FaceLobes {
    std::array<FaceLobe, 3> face{};
    std::size_t count = 0;

    std::size_t size() const { return count; }
    const FaceLobe &operator[](std::size_t f) const { return face[f]; }
    const FaceLobe *begin() const { return face.data(); }
    const FaceLobe *end() const { return face.data() + count; }
};

// A face's outward normal, the face given as a FaceExit or as its normal (projectedArea's faces).
inline const glm::dvec3 &outwardNormal(const FaceExit &face) { return face.normal; }
inline const glm::dvec3 &outwardNormal(const FaceLobe &face) { return face.normal; }
inline const glm::dvec3 &outwardNormal(const glm::dvec3 &normal) { return normal; }

// A camera looking along -w sees a voxel through those of its faces that face w, each in proportion to its projected
// area c_f = max(0, n_f . w) (per unit face area, n_f the face's outward normal), and a beam travelling along -w enters
// them in the same proportion (edgeLobe's mix, peakSeenThroughFaces, the beam's share of each face in surfaceLight).
// The faces' projected area sum_f c_f (0 where none faces w), calling seen(f, c_f) for each face f (its index in
// `faces`) that faces w, in order.
template <typename Faces, typename Seen>
double projectedArea(const Faces &faces, const glm::dvec3 &w, const Seen &seen) {
    double area = 0.0;
    for (std::size_t f = 0; f < faces.size(); ++f)
        if (const double c = glm::dot(outwardNormal(faces[f]), w); c > 0.0) area += c, seen(f, c);
    return area;
}
template <typename Faces>
double projectedArea(const Faces &faces, const glm::dvec3 &w) {
    return projectedArea(faces, w, [](std::size_t, double) {});
}

// The lobe to store for such a voxel. A camera looking along -w sees it through the faces that face w, each
// in proportion to its projected area, so what the voxel shows towards w is the mix
//   T(w) = sum_f max(0, n_f . w) max(0, L_f(w)) / sum_f max(0, n_f . w)
// over every direction that sees a face (3/4 of the sphere at an edge, where one smooth patch would only
// hold a hemisphere). The lobe: axis along T's first moment, k fitted by least squares in relative error
// weighted by the faces' projected area, l0 keeping the light that leaves through the faces and no larger
// than T's largest value (exitLobe's rule: a lobe pointing into the snow would hide its light).
SourceLobe edgeLobe(const std::vector<FaceExit> &faces);

// The lobe for the air diagonal to a sharp edge or corner, beyond all of `faces` (two or three flat faces at right
// angles, each with the lobe the air across it carries): the faces' light reaches that air only travelling away from
// every one of them (seen along -w through it, a face lies behind only where n_f . w > 0 for each f; towards any other
// w the snow lies beside the way). So it shows towards w the faces' mix T(w) = sum_f c_f L_f(w) / sum_f c_f
// (c_f = n_f . w, edgeLobe's) where every face faces w, and none of their light elsewhere. The lobe: axis and k from T's
// first moment (k = |mean of T w| / mean of T), l0 keeping the light T carries over the directions it is seen from, as
// exitLobe keeps a face's over its hemisphere (k from T's moment alone, with l0 its mean over the whole sphere, read
// the edge's air too dark from within: a convex edge under the sky 1.02 of the inside against the Monte Carlo's 1.09).
// The faces' lobes' mean (before) showed a camera above box_sharp's lit wall's foot the wall's light in the corner
// air below the bottom's plane, where the light climbing the wall never passes: that block +50 %, with this +30 %
// (docs/benchmarks.md, box-edge, corner-air).
SourceLobe lobeBeyondFaces(const FaceLobes &faces);

// Of a sharp voxel's peaked lobe about the unit `axis` (the suns returned sharply forwards, stored as the voxel's
// radiance over all its air faces), the part its one value shows. Air face f of normal normals[f] sends its own
// radiance, radiance[f] times the voxel's (its share of the peak over its share of the faces' area); a camera towards
// w sees the voxel through the faces that face w in proportion to their projected area (edgeLobe's mix), so along the
// lobe's axis, where it is seen, the voxel shows
//   sum_f radiance[f] max(0, n_f . axis) / sum_f max(0, n_f . axis)
// times the stored lobe (1 where no face faces the axis). A lit top's grazing return along the shadowed side beside
// it is seen through the top's thin projected area, not through the whole side (docs/benchmarks.md, corner-lean).
double peakSeenThroughFaces(const std::vector<glm::dvec3> &normals, const std::vector<double> &radiance,
                            const glm::dvec3 &axis);

// The sun a sharp edge voxel's air face of normal n takes in through its density ramp beyond the edge, per unit face
// area, the way the beam travels being -w: the beam crossing a lit neighbouring face's plane (n_a . w > 0, n_a at right
// angles to n) within the ramp outside n's half-density plane, where no face's intake counts it (half a voxel wide:
// the trilinear fill falls from 1/2 there to 0), caught by that ramp while travelling along the face (n . w = 0: all of
// it) or away from it (n . w < 0: along a chord), and scattered back through n's plane into the snow. The fill
// 1/2 - u at u voxels out gives the way from u0 the optical depth tau (1/2 - u0)^2 / (2 |n . w|), tau the voxel's at the
// snow's density; caught, averaged over u0: 1 - sqrt(pi / a) erf(sqrt(a) / 2), a = tau / (2 |n . w|). Scattered once
// by HG(g), the share heading back into the snow: 1/2 along the face, less as the beam leaves it. slab_thick's grazing
// side beside its lit side (the sun in the side's plane): the Monte Carlo's light there fell 43 % with that strip
// screened off, the bake's 18 % (docs/benchmarks.md, edge-skim). 0 where the face itself faces the light (its own
// intake holds those rays).
double skimmedThroughRamp(const std::vector<glm::dvec3> &normals, const glm::dvec3 &n, const glm::dvec3 &w,
                          double voxelOpticalDepth, double g);

// Each face's form taken as its mean over the face where the light beneath it also leaves through the faces beside
// it. Near their shared edge the snow's fluence is one for both faces: by symmetry the two exits meet at the edge at
// their mean, and the difference relaxes away from it over the fluence's lateral length, the diffusion length
// 1 / sigma_eff (sigma_eff = sqrt(3 sigma_a sigma_tr)): f + (g - f) / 2 exp(-x sigma_eff h), x across the voxel in
// voxels. The face's mean moves by kappa (g - f), kappa = (1 - exp(-s)) / (2 s), s = sigma_eff h, towards each
// neighbour g at right angles (f, g: the forms' mean radiance over their hemispheres); kappa <= 1/2, the two faces'
// mean at most, and what the brighter face loses the darker gains (equal areas). Where the faces carry the same light
// nothing moves; over a dark ground a convex edge's top falls towards its side (docs/benchmarks.md, edge-corner,
// edge-relax). Only where snow lies beneath every face (no two air faces opposite: the edges and corners of snow
// thicker than a voxel); relaxed, a cloud of small lumps read 0.93 of the Monte Carlo (test_bake_accuracy.py).
void relaxTowardsNeighbours(std::vector<FaceExit> &faces, double voxelInDiffusionLengths);

}  // namespace firn
