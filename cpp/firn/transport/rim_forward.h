#pragma once

#include <glm/common.hpp>
#include <glm/exponential.hpp>
#include <glm/vec3.hpp>

namespace firn {

// Light from behind other snow's fuzzy rims that they scatter forwards, onto a surface patch along one of its sky
// rays (W/m^2/sr, per channel; docs/bake.md Limits, "rims crossed forwards"). The sky ray took the light behind
// uncollided, e^{-tau} `behind` (the sky, an occluder's one reflection), and the gathering the snow's baked
// radiance along it, `rims` = (1 - e^{-tau}) S (S: the rims' pieces' exit light). A rim scatters what crosses it
// mostly forwards: the similarity beam lets e^{-tau_tr} of it through, e^{-tau_tr} - e^{-tau} more than the
// uncollided part. S, a smooth lobe of the piece's light, holds the light from behind wherever it is as bright as
// that (under a uniform sky S = `behind`, and counting the forward part again counted it twice: a cube of 216
// lumps +18 %), so only the background's excess over S is added. `column`: the snow's mass along the ray (kg/m^2);
// `extinction`, `reduced`: sigma_t and sigma_tr per density (m^2/kg).
inline glm::dvec3 forwardThroughRims(const glm::dvec3 &extinction, const glm::dvec3 &reduced, double column,
                                     const glm::dvec3 &behind, const glm::dvec3 &rims) {
    const glm::dvec3 uncollided = glm::exp(-extinction * column);
    const glm::dvec3 forward = glm::exp(-reduced * column) - uncollided;
    const glm::dvec3 S = rims / glm::max(1.0 - uncollided, 1e-6);
    return forward * glm::max(behind - S, 0.0);
}

}  // namespace firn
