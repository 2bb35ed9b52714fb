#pragma once

#include <glm/vec3.hpp>

#include "firn/transport/source_lobe.h"

namespace firn {

// The lobe to store in the air across a snow face: the source function of the face's density ramp, which the
// renderer shows as emission (docs/bake.md's opening, Method 7). The ramp scatters towards w the face's exit radiance,
// which travels only outwards (nothing comes up from below the face):
//   J(w) = albedo integral over n . w' > 0 of L(w') p_g(w . w') dw'   (W/m^2/sr),
// L the face's stored lobe lobeRadiance(l0, l1, w') on its outward hemisphere (n the face's outward normal, unit),
// p_g Henyey-Greenstein. The face's lobe itself, shown there before, went on past its hemisphere: across a flat face
// it showed a camera looking into the snow (n . w -0.71) 3.8 times J (a k 0.24 face, g 0.7) and grazing views 0.66
// of it (docs/benchmarks.md, box-foot-b, back-tail). Stored as one lobe:
//   l0 = J's mean, exact: albedo times the face lobe's mean over its hemisphere (p_g keeps the light: mean 1);
//   axis along J's first moment, which is g times L's over the hemisphere (HG's Legendre terms multiply), so in the
//   plane of n and the face's axis;
//   k by least squares in radiance over the sphere with that mean (cameras see the air from every side): J is flatter
//   than any HG lobe (a k 0.24 face, g 0.7: J's back 0.16 and normal 2.4 times its mean; HG of k 0.43 by that ratio
//   is 0.40 grazing, J 0.85), so no k holds it all; the fit keeps the radiance's error least where the light is.
// From a table over the face's k, the angle between its axis and n, and g (in steps of 0.05), each g's part built on
// first use (ramp_lobe.cpp).
SourceLobe rampLobe(double l0, const glm::dvec3 &l1, const glm::dvec3 &normal, double g, double albedo);

}  // namespace firn
