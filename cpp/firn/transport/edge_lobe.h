#pragma once

#include <vector>

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

// The lobe to store for such a voxel. A camera looking along -w sees it through the faces that face w, each
// in proportion to its projected area, so what the voxel shows towards w is the mix
//   T(w) = sum_f max(0, n_f . w) max(0, L_f(w)) / sum_f max(0, n_f . w)
// over every direction that sees a face (3/4 of the sphere at an edge, where one smooth patch would only
// hold a hemisphere). The lobe: axis along T's first moment, k fitted by least squares in relative error
// weighted by the faces' projected area, l0 keeping the light that leaves through the faces and no larger
// than T's largest value (exitLobe's rule: a lobe pointing into the snow would hide its light).
SourceLobe edgeLobe(const std::vector<FaceExit> &faces);

}  // namespace firn
