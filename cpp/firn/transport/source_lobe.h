#pragma once

#include <algorithm>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

namespace firn {

// The angular form of the baked source function (docs/vdb-contract.md), per channel: one Henyey-Greenstein
// lobe read from the stored l0 (firn_source) and l1 (firn_source_x/y/z),
//   S(w) = l0 (1 - k^2) / (1 + k^2 - 2 k cos)^1.5,   k = min(|l1| / (3 l0), kMaxLobeAnisotropy) (0 if l0 <= 0),
//   cos = w . l1 / |l1|,
// that is l0 4 pi HG(k, cos): the same mean (l0) and first moment (4 pi l1 / 3) as the linear form l0 + l1 . w,
// never negative, and exact for light scattered once from a beam (l1 = 3 g l0 towards the beam's travel, k = g).
// w is the unit direction towards the viewer.
constexpr double kMaxLobeAnisotropy = 0.95;  // firncore.LOBE_MAX_ANISOTROPY: the add-on's material clamps k with it
double lobeRadiance(double l0, const glm::dvec3 &l1, const glm::dvec3 &w);

// The second, peaked lobe of the source function (docs/vdb-contract.md): the light that keeps a beam's
// direction (single scattering of the suns' and lamps' beams, beams crossing the snow to a far surface), beside
// the broad lobe above, which one lobe cannot hold together with it. Per channel its mean p0 (firn_source_peak),
// for all channels one axis and k from the grey first moment p1 = 3 k m mean(p0) (firn_source_peak_l1):
//   S_peak(w) = p0 / mean(p0) lobeRadiance(mean(p0), p1, w)   (0 where mean(p0) <= 0),
// mean(p0) = (p0.r + p0.g + p0.b) / 3. Moments sum: peaks along different axes add to one of smaller k.
double peakRadiance(double p0, double p0Mean, const glm::dvec3 &p1, const glm::dvec3 &w);
// The three channels' peaked lobes at once (p0 per channel): their shape, the channels' mean's lobe, worked out
// once (the gathering's samples spent a third of their lobes' time on it twice more); the same values as
// peakRadiance's, bit for bit.
glm::dvec3 peakRadiance(const glm::dvec3 &p0, const glm::dvec3 &p1, const glm::dvec3 &w);

// What the grids store for a lobe of mean l0 and anisotropy k about the unit axis m: l1 = 3 k l0 m.
struct SourceLobe {
    double l0 = 0.0;
    glm::dvec3 l1{0.0};
};

// The lobe to store for a surface whose exit radiance, over the outgoing hemisphere w . normal > 0, is
// L(w) = e0 + e1 . w (the surface model's linear form): axis along e1, k fitted to max(0, L) by least squares
// in relative error weighted by projected solid angle (what cameras see of the surface), and l0 so that the
// exitance (the flux of L through the surface, its negative parts included: the model's energy) is kept; none
// where that is not positive. l0 stays within e0 + |e1|, the form's largest value: a lobe pointing into the
// snow would hide most of its light where no camera looks, and the renderer interpolates l0 with the
// neighbours'. A surface's escape shape is flatter than a lobe of the linear form's first moment: the escape
// function u = 3/7 (1 + 2 mu) reads as k = 2/3 by moments (5 times too bright seen along the normal), k = 0.24
// fitted (within 9 % for mu >= 0.2, +32 % at grazing views). From a table over |e1| / (e0 + |e1|) and the
// angle between e1 and the normal, built on first use.
SourceLobe exitLobe(double e0, const glm::dvec3 &e1, const glm::dvec3 &normal);

// The anisotropy of the peaked lobe a beam's light keeps where it scatters once or crosses the snow to a far
// surface: the snow's g, within what a stored lobe holds.
inline double crossingAnisotropy(double g) { return std::min(g, kMaxLobeAnisotropy); }

// The broad lobe per channel (W/m^2/sr): mean l0 and first moment 4 pi l1 / 3 (lobeRadiance). A surface's
// radiance has no other (the peaked lobe is the beams' light inside the snow).
struct BroadLobe {
    glm::vec3 l0{0.0f};
    glm::mat3 l1{0.0f};  // column c: the vector for channel c
};

// The source function in one voxel, per channel (W/m^2/sr), as the grids store it: the broad lobe and the
// peaked lobe of mean peak0 and grey first moment peak1 (peakRadiance).
struct Source : BroadLobe {
    glm::vec3 peak0{0.0f}, peak1{0.0f};

    // Adds a peaked lobe of mean l0 per channel and anisotropy k about the unit axis m (where its light goes).
    void addPeak(const glm::dvec3 &mean, double k, const glm::dvec3 &m) {
        peak0 += glm::vec3(mean);
        peak1 += glm::vec3(k * (mean.x + mean.y + mean.z) * m);  // 3 k m (the channels' mean)
    }
    // Sums and means of sources, part by part: adds w times o; divides by d.
    void add(const Source &o, float w = 1.0f) {
        l0 += w * o.l0, l1 += w * o.l1, peak0 += w * o.peak0, peak1 += w * o.peak1;
    }
    void divideBy(float d) { l0 /= d, l1 /= d, peak0 /= d, peak1 /= d; }
};

}  // namespace firn
