#include "firn/transport/bake_sun_downstream.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/work_check.h"

namespace firn::bake {

namespace {

// Where a half-space returns a beam entering at cos mu0, relative to where it entered, in transport mean free
// paths 1/sigma_tr: the mean displacement along the beam's tangential travel and the spread about it (standard
// deviation along it). Monte Carlo, bench/halfspace_displacement.py (100,000 photons), the means of omega 0.98,
// g 0.85 and omega 0.9, g 0.6 (within 0.1 of omega 0.9999, g 0.85 for the mean), at mu0 0.05, 0.15, 0.3, 0.5, 0.7, 1.
struct Displacement {
    double mean, spread;
};
Displacement halfSpaceDisplacement(double mu0) {
    static constexpr std::array<double, 6> kMu{0.05, 0.15, 0.3, 0.5, 0.7, 1.0};
    static constexpr std::array<double, 6> kMean{0.58, 0.67, 0.73, 0.71, 0.60, 0.0};
    static constexpr std::array<double, 6> kSpread{0.81, 0.93, 1.05, 1.17, 1.26, 1.37};
    std::size_t k = 1;
    while (k + 1 < kMu.size() && mu0 > kMu[k]) ++k;
    const double f = std::clamp((mu0 - kMu[k - 1]) / (kMu[k] - kMu[k - 1]), 0.0, 1.0);
    return {kMean[k - 1] + f * (kMean[k] - kMean[k - 1]), kSpread[k - 1] + f * (kSpread[k] - kSpread[k - 1])};
}

// The width (voxels) of the neighbourhood the sun each patch returns at once is averaged over before it moves
// downstream (neighbourhoodOutflow's reach): a Gaussian giving the face neighbours 0.61 of the voxel's own weight,
// the edge neighbours 0.37. That light follows the sun's cosine and shadow, which change within a voxel at a
// terminator or a shadow's edge: averaged over the whole 3^3 block of a 1 cm staircase, ball_issue's plateau just
// past its terminator took its lit neighbours' (seen from the side, the sun a voxel past +46 % where 0.5 cm voxels
// read +5 %; now +38 %) and bumpy_plate's shadow edges blurred (10.0 -> 9.4 %). Per voxel alone the staircase lets
// it out unevenly (ball_clean +0.4 points); at 0.8 ball_grey lost 0.1 point (docs/benchmarks.md, plateau-sun).
constexpr double kAtOnceReach = 1.0;

}  // namespace

// Surface voxel i's downstream kernel (SunReturned::downstream, spread; m): the beams' displacements weighted
// by the power each lets in, on the snow beneath the patch (channel ch's sigma_tr: one kernel for the three).
void downstreamKernel(const Scene &scene, const IncidentLight &light, const SurfaceTerms &sys, const Channel &ch,
                      const SnowTopology &topo, std::size_t i, SunReturned &surface) {
    const glm::dvec3 n = topo.patches[i].normal, centre = scene.medium->voxelCentre(topo.coord[i]);
    const double transportPath = 1.0 / ch.sigmaTr(densityBeneath(topo, i, n));  // m
    double power = 0.0, spread = 0.0;
    glm::dvec3 downstream(0.0);
    for (std::size_t s = 0; s < light.beams.size(); ++s) {
        const double P = sys.sunIn[s][i];
        if (P <= 0.0) continue;
        // A lamp's way at the voxel centre, not the patch's surface (sunIn's cosine): from the surface the lobe and
        // this kernel read ball_grey's limb 1.22 -> 1.35 of the Monte Carlo (docs/benchmarks.md, lamp-near).
        const glm::dvec3 d = -towardsBeam(scene, s, centre);
        const Displacement k = halfSpaceDisplacement(std::clamp(-glm::dot(d, n), 0.05, 1.0));
        downstream += P * k.mean * travelAlong(d, n);
        spread += P * k.spread, power += P;
    }
    if (power <= 0.0) return;
    surface.downstream = glm::vec3(transportPath / power * downstream);
    surface.spread = float(transportPath * spread / power);
}

namespace {

// The rotation taking unit vector `from` to unit vector `to` (the shorter way; from . to > -1), applied to v.
glm::dvec3 rotatedWith(const glm::dvec3 &v, const glm::dvec3 &from, const glm::dvec3 &to) {
    const glm::dvec3 axis = glm::cross(from, to);  // sin times the unit axis
    const double cos = glm::dot(from, to);
    return cos * v + glm::cross(axis, v) + axis * (glm::dot(axis, v) / (1.0 + cos));
}

// The weights surface voxel i's downstream kernels (one per channel) give surface voxel j of its 3^3 block (before
// normalizing): a Gaussian of the half-space's displacement (SunReturned::downstream, spread) in i's tangent plane,
// times j's patch area and the cosine between the normals; smooth patches only. a, b: i's and j's patches; d: j's
// voxel less i's. A channel whose kernel is the one before's to the bit (a white sun's: its power alike) takes that
// weight, the same number without its exponential.
glm::dvec3 downstreamWeights(const SurfacePatch &a, const std::array<const SunReturned *, 3> &from,
                             const SurfacePatch &b, const openvdb::Coord &d, double h) {
    const double facing = glm::dot(a.normal, b.normal);
    if (b.sharp || facing <= 0.0) return glm::dvec3(0.0);
    glm::dvec3 step = h * glm::dvec3(d.x(), d.y(), d.z());
    step -= glm::dot(step, a.normal) * a.normal;
    const double weighted = facing * b.area;
    glm::dvec3 weight;
    for (int c = 0; c < 3; ++c) {
        const SunReturned &kernel = *from[c];
        if (c > 0 && kernel.downstream == from[c - 1]->downstream && kernel.spread == from[c - 1]->spread) {
            weight[c] = weight[c - 1];
            continue;
        }
        if (kernel.spread <= 0.0f) {
            weight[c] = d == openvdb::Coord(0) ? 1.0 : 0.0;
            continue;
        }
        const glm::dvec3 off = step - glm::dvec3(kernel.downstream);
        weight[c] = weighted * std::exp(-glm::dot(off, off) / (2.0 * double(kernel.spread) * double(kernel.spread)));
    }
    return weight;
}

}  // namespace

// The three channels' sun light each smooth patch returns at once (`sun`; its atOnce averaged over the neighbourhood as
// the outflow is, for a staircase lets it out unevenly, but within kAtOnceReach), where it leaves: over the surface
// voxels of its 3^3 block by downstreamWeights, the weights of each sender summing to one (downstreamWeights keeps the
// power it spreads), the forms turned with the normal, added to the receivers' returned light; what escaped at once is
// taken out of their `leaving`. A flat, evenly lit surface receives what it sends (the flat slabs unchanged); past a
// terminator the patches downstream take what entered before it (docs/bake.md, Method 5). The channels share each
// pair's reads (the loops are bound by them).
void sunLeavingDownstream(const SnowTopology &topo, const std::array<SurfaceValues<SunReturned>, 3> &sun, double h,
                          SurfaceValues<SurfaceLight> &out, const SubProgress &progress) {
    // By surface slot: each neighbour's slot looked up once.
    const std::vector<std::int32_t> &slot = *topo.surfaceSlot;
    const auto &patch = topo.patches.values();
    auto sent = [&](std::int32_t s) {
        return std::array<const SunReturned *, 3>{&sun[0].values()[s], &sun[1].values()[s], &sun[2].values()[s]};
    };
    std::vector<glm::vec3> total(topo.surfaceVoxels(), glm::vec3(0.0f));   // each sender's weights' sum
    std::vector<glm::vec3> atOnce(topo.surfaceVoxels(), glm::vec3(0.0f));  // W sent, averaged
    auto smooth = [&](std::int32_t s) { return s >= 0 && patch[s].isSurface() && !patch[s].sharp; };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        WorkCheck work(progress);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const std::int32_t si = slot[i];
            if (!smooth(si)) continue;
            work.add(WorkCheck::kVoxel);
            const auto atOnceOf = [&](std::size_t j) {
                return glm::dvec3(sun[0][j].atOnce, sun[1][j].atOnce, sun[2][j].atOnce);
            };
            const auto [leaving, area] =
                neighbourhoodOutflow<glm::dvec3>(topo, i, patch[si].normal, atOnceOf, kAtOnceReach);
            atOnce[si] = glm::vec3(leaving / area * double(patch[si].area));
            const auto from = sent(si);
            glm::dvec3 sum(0.0);
            for (std::size_t k = topo.neighbourhoodStart[i]; k < topo.neighbourhoodStart[i + 1]; ++k) {
                const std::uint32_t j = topo.neighbourhood[k];
                sum += downstreamWeights(patch[si], from, patch[slot[j]], topo.coord[j] - topo.coord[i], h);
            }
            total[si] = glm::vec3(sum);
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        WorkCheck work(progress);
        for (std::size_t j = range.begin(); j != range.end(); ++j) {
            const std::int32_t sj = slot[j];
            if (!smooth(sj)) continue;
            work.add(WorkCheck::kVoxel);
            const glm::dvec3 to = patch[sj].normal;
            glm::vec3 l0(0.0f);
            glm::mat3 l1(0.0f);  // column c: channel c's
            for (std::size_t k = topo.neighbourhoodStart[j]; k < topo.neighbourhoodStart[j + 1]; ++k) {
                const std::uint32_t i = topo.neighbourhood[k];
                const std::int32_t si = slot[i];
                if (!smooth(si)) continue;
                const auto from = sent(si);
                const glm::dvec3 weights =
                    downstreamWeights(patch[si], from, patch[sj], topo.coord[j] - topo.coord[i], h);
                for (int c = 0; c < 3; ++c) {
                    if (!(total[si][c] > 0.0f)) continue;
                    const double w = weights[c] / total[si][c];
                    if (w <= 0.0) continue;
                    // what escaped at once in the escape function's shape
                    l0[c] += float(w * (from[c]->l0 + 3.0 / 7.0 * atOnce[si][c]));
                    l1[c] += glm::vec3(w * (rotatedWith(glm::dvec3(from[c]->l1), patch[si].normal, to) +
                                            6.0 / 7.0 * atOnce[si][c] * to));
                }
            }
            SurfaceLight &received = out.surface(j);
            for (int c = 0; c < 3; ++c) {
                received.returned.l0[c] += l0[c];
                received.returned.l1[c] += l1[c];
                received.leaving[c] -= sun[c][j].atOnce;
            }
        }
    });
}

}  // namespace firn::bake
