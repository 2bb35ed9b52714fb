#include "firn/transport/bake_source_function.h"

#include <algorithm>
#include <atomic>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/mat4x4.hpp>
#include <glm/mat4x3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/bake_diffusion_system.h"
#include "firn/transport/edge_lobe.h"
#include "firn/transport/monte_carlo.h"
#include "firn/util/sampling.h"
#include "firn/util/work_check.h"

namespace firn::bake {

namespace {

// The source function inside unknowns `range` (out[i - range.begin()], zero on entry) from the three channels'
// fluence: S = omega / (4 pi) (phi + 3 g F . w), F = -D grad phi, plus the beams scattered once (the peaked
// lobe). After the solves (during them it would take 48 bytes per unknown).
void insideSource(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                  const std::array<UnwrittenVector<double>, 3> &phi, const tbb::blocked_range<std::size_t> &range,
                  Source *out) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    const double h = medium.voxelSize();
    for (int c = 0; c < 3; ++c) {
        const Channel ch{optics.extinctionPerDensity, optics.albedo[c], optics.g};
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            glm::dvec3 gradient(0.0);
            for (int axis = 0; axis < 3; ++axis) {
                const std::int32_t lo = topo.link[i][2 * axis], hi = topo.link[i][2 * axis + 1];
                const double pLo = lo >= 0 ? phi[c][lo] : phi[c][i], pHi = hi >= 0 ? phi[c][hi] : phi[c][i];
                const int span = (lo >= 0) + (hi >= 0);
                gradient[axis] = span ? (pHi - pLo) / (span * h) : 0.0;
            }
            const double D = 1.0 / (3.0 * ch.sigmaTr(topo.density[i]));
            Source &S = out[i - range.begin()];
            S.l0[c] = ch.omega * kInvFourPi * phi[c][i];
            S.l1[c] = ch.omega * kInvFourPi * -3.0 * ch.g * D * gradient;
            if (c < 2) continue;
            // The beams scattered once: the peaked lobe, all channels at once.
            const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]);
            for (std::size_t s = 0; s < light.beams.size(); ++s) {
                const glm::dvec3 beam = glm::dvec3(light.beams[s].atVoxel[i]) * glm::dvec3(optics.albedo) * kInvFourPi;
                if (beam.x + beam.y + beam.z > 0.0)
                    S.addPeak(beam, crossingAnisotropy(optics.g), -towardsBeam(scene, s, centre));
            }
        }
    }
}

// Calls f(i) for every surface voxel i, in parallel, counting each as a voxel's work for progress and cancel.
template <typename F>
void forEachSurfaceVoxel(const SnowTopology &topo, const SubProgress &progress, const F &f) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        WorkCheck work(progress);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!topo.patches[i].isSurface()) continue;
            work.add(WorkCheck::kVoxel);
            f(i);
        }
    });
}

}  // namespace

// Radiance leaving each surface voxel. The returned part is the voxel's own (over its patch's area); the
// light leaving in the escape function's shape is averaged over the voxel's neighbourhood (surface voxels
// of its 3^3 block facing the same way, weighted by the cosine between the normals, by area): a voxel
// staircase spreads the diffusion's outflow unevenly between steps, though the light itself varies only
// over a few transport mean free paths. The shape follows the voxel's own normal. Voxels on a sharp edge
// are left out of their neighbours' averages: their outflow leaves through two or three faces at once (the
// lit top's light spread down a shadowed side a voxel or two, bench/bake_suite.py box_sharp: 8.7 % mean
// error with them, 5.4 % without).
SurfaceValues<Source> surfaceRadiance(const VolumeOptics &optics, const SnowTopology &topo,
                                      const SurfaceValues<SurfaceLight> &solved, const SubProgress &progress) {
    SurfaceValues<Source> out(topo.surfaceSlot, topo.surfaceVoxels());
    forEachSurfaceVoxel(topo, progress, [&](std::size_t i) {
        const glm::dvec3 &n = topo.patches[i].normal;
        const auto [leaving, area] = neighbourhoodOutflow<glm::dvec3>(
            topo, i, n, [&](std::size_t j) { return glm::dvec3(solved[j].leaving); });
        const glm::dvec3 exitance = leaving / area;  // W/m^2, area > 0: the voxel itself has weight 1
        const double own = kPi * topo.patches[i].area;
        const BroadLobe &returned = solved[i].returned;
        for (int c = 0; c < 3; ++c) {  // the exit radiance e0 + e1 . w, stored as its fitted lobe
            const SourceLobe lobe =
                topo.patches[i].sharp
                    ? SourceLobe{returned.l0[c], glm::dvec3(returned.l1[c])}  // fitted already
                    : exitLobe(returned.l0[c] / own + exitance[c] * (3.0 / 7.0 / kPi),
                               glm::dvec3(returned.l1[c]) / own + exitance[c] * 6.0 / 7.0 / kPi * n, n);
            const SourceLobe shown = withCrossing(lobe, solved[i], topo.patches[i].area, c, optics.g);
            out.surface(i).l0[c] = float(shown.l0);
            out.surface(i).l1[c] = glm::vec3(shown.l1);
        }
        out.surface(i).peak0 = solved[i].peak0, out.surface(i).peak1 = solved[i].peak1;
    });
    return out;
}

SurfaceValues<float> skyShares(const SnowTopology &topo, const SurfaceValues<SurfaceLight> &solved,
                               const SurfaceValues<Source> &radiance, bool apart, const SubProgress &progress) {
    if (!apart) return {};
    SurfaceValues<float> out(topo.surfaceSlot, topo.surfaceVoxels());
    forEachSurfaceVoxel(topo, progress, [&](std::size_t i) {
        const glm::dvec3 &n = topo.patches[i].normal;
        const double leaving = neighbourhoodOutflow<double>(
            topo, i, n, [&](std::size_t j) { return double(solved[j].leaving.y); }).first;
        const double sky = neighbourhoodOutflow<double>(
            topo, i, n, [&](std::size_t j) { return double(solved[j].skyLeaving); }).first;
        const double l0 = radiance[i].l0.y, crossing = solved[i].crossing.y / topo.patches[i].area;
        const double broad = l0 > 0.0 ? std::clamp(1.0 - crossing / l0, 0.0, 1.0) : 1.0;
        out.surface(i) = float(leaving > 0.0 ? std::clamp(sky / leaving, 0.0, 1.0) * broad : 1.0);
    });
    return out;
}

PeakedLobes rampPeaks(const Scene &scene, const SnowTopology &topo, const SurfaceValues<SurfaceLight> &solved) {
    PeakedLobes out;
    if (scene.lamps.empty()) return out;
    PeakedLobes::Peaks peaks;
    for (std::size_t i = 0; i < topo.size(); ++i)
        if (topo.patches[i].isSurface())
            if (const SurfaceLight &s = solved[i]; s.rampPeak0 != glm::vec3(0.0f) || s.rampPeak1 != glm::vec3(0.0f))
                peaks.push_back({std::uint32_t(i), s.rampPeak0, s.rampPeak1});
    out.appendAll(peaks);
    return out;
}

namespace {

// Inside the snow, within a few mean free paths of the surface, a camera ray still sees its surface
// voxel's radiance: those voxels take it over (SnowTopology's shell), so where the ray reaches optical
// depth 1 does not matter; deeper voxels keep their own source function, which only thin snow shows.
// In place: out (insideSource's for unknowns `range`) becomes the source function.
void composeSource(const SnowTopology &topo, const SurfaceValues<Source> &surface,
                   const tbb::blocked_range<std::size_t> &range, Source *out) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
        const std::int32_t owner = topo.shellOwner[i];
        const float w = topo.shellWeight[i];
        Source &S = out[i - range.begin()];
        if (owner >= 0) {
            S.l0 = w * surface[owner].l0 + (1.0f - w) * S.l0;
            S.l1 = w * surface[owner].l1 + (1.0f - w) * S.l1;
            S.peak0 = w * surface[owner].peak0 + (1.0f - w) * S.peak0;
            S.peak1 = w * surface[owner].peak1 + (1.0f - w) * S.peak1;
        }
    }
}

}  // namespace

// The source function of every unknown: inside (insideSource) composed with the surface's (composeSource), a
// block of unknowns at a time. Traced voxels hold their Monte Carlo source instead of the diffusion's, also
// where a surface's values are carried beyond the snow: a thin object's surface voxels are traced, and its rim
// shows their light.
SourceValues sourceFunction(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                            const std::array<UnwrittenVector<double>, 3> &phi, const SurfaceValues<Source> &surface,
                            const MonteCarloVoxels &traced, const SubProgress &progress) {
    constexpr std::size_t kBlock = 1024;
    SourceValues out;
    out.broad.resize(topo.size());
    std::vector<PeakedLobes::Peaks> peaked((topo.size() + kBlock - 1) / kBlock);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, peaked.size(), 1), [&](const auto &blocks) {
        TracedIndex tracedIndex(traced);
        std::vector<Source> values;
        WorkCheck work(progress);
        for (std::size_t b = blocks.begin(); b != blocks.end(); ++b) {
            const tbb::blocked_range<std::size_t> range(b * kBlock, std::min(topo.size(), (b + 1) * kBlock));
            work.add(WorkCheck::kVoxel * range.size());
            values.assign(range.size(), Source{});
            insideSource(scene, topo, light, phi, range, values.data());
            composeSource(topo, surface, range, values.data());
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                Source &S = values[i - range.begin()];
                if (const std::int32_t t = tracedIndex.getValue(topo.coord[i]); t >= 0) S = traced.source[t];
                out.broad[i] = S;
                PeakedLobes::append(peaked[b], i, S);
            }
        }
    });
    std::vector<const PeakedLobes::Peaks *> blocks;
    for (const PeakedLobes::Peaks &block : peaked) blocks.push_back(&block);
    out.peaked.appendAll(blocks, std::vector<std::size_t>(blocks.size(), 0));
    return out;
}

// REFERENCE quality: the radiance leaving each surface voxel, path traced from 12 directions around
// its normal, fitted by least squares with a linear form, stored as that form's fitted lobe; on a sharp edge
// from 12 directions around each air face's normal, stored as the lobe fitted to the faces' forms (edgeLobe).
void referenceSurface(const Scene &scene, const SnowTopology &topo, int samples, std::uint64_t seed,
                      SurfaceValues<Source> &out, const SubProgress &progress) {
    const MonteCarloReference reference(scene);
    const double h = scene.medium->voxelSize();
    std::vector<std::size_t> surface;
    for (std::size_t i = 0; i < topo.size(); ++i)
        if (topo.patches[i].isSurface()) surface.push_back(i);
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, surface.size(), 1), [&](const auto &range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            progress.throwIfCancelled();
            const std::size_t i = surface[k];
            const glm::dvec3 centre = scene.medium->voxelCentre(topo.coord[i]);
            // The linear form e0 + e1 . w of each channel fitted to the radiance seen from 12 directions around n.
            auto fitAround = [&](const glm::dvec3 &n, std::uint64_t stream) {
                glm::dmat4 normal(0.0);
                glm::dmat4x3 rhs(0.0);  // column m: basis function m against the three channels
                int d = 0;
                for (double mu : {0.95, 0.7, 0.35})
                    for (int a = 0; a < 4; ++a, ++d) {
                        const glm::dvec3 w = directionAround(n, mu, kPi * (0.5 * a + 0.25 * (mu < 0.5)));
                        const Ray ray{centre + 3.0 * h * w, -w};
                        const Rgb L = reference.estimate(ray, samples, seed, stream * 12 + d).mean;
                        const glm::dvec4 basis(1.0, w.x, w.y, w.z);
                        normal += glm::outerProduct(basis, basis);
                        for (int m = 0; m < 4; ++m) rhs[m] += basis[m] * L;
                    }
                const glm::dmat4 inverse = glm::inverse(normal);
                std::array<glm::dvec4, 3> out;
                for (int c = 0; c < 3; ++c) {
                    glm::dvec4 v;
                    for (int m = 0; m < 4; ++m) v[m] = rhs[m][c];
                    out[c] = inverse * v;
                }
                return out;
            };
            const SurfacePatch &patch = topo.patches[i];
            if (patch.sharp) {  // each air face's own form, then the lobe of what cameras see of them (edgeLobe)
                std::array<std::vector<FaceExit>, 3> faces;
                for (int f = 0; f < 6; ++f) {
                    if (patch.share[f] <= 0.0f) continue;
                    const auto form =
                        fitAround(faceNormal(f), topo.size() + i * 6 + std::uint64_t(f));  // streams of its own
                    for (int c = 0; c < 3; ++c)
                        faces[c].push_back({faceNormal(f), form[c][0], glm::dvec3(form[c][1], form[c][2], form[c][3])});
                }
                for (int c = 0; c < 3; ++c) {
                    const SourceLobe lobe = edgeLobe(faces[c]);
                    out.surface(i).l0[c] = float(lobe.l0);
                    out.surface(i).l1[c] = glm::vec3(lobe.l1);
                }
            } else {
                const auto form = fitAround(patch.normal, i);
                for (int c = 0; c < 3; ++c) {
                    const SourceLobe lobe =
                        exitLobe(form[c][0], glm::dvec3(form[c][1], form[c][2], form[c][3]), patch.normal);
                    out.surface(i).l0[c] = float(lobe.l0);
                    out.surface(i).l1[c] = glm::vec3(lobe.l1);
                }
            }
            out.surface(i).peak0 = out.surface(i).peak1 = glm::vec3(0.0f);  // the traced radiance is all of it
            progress.report(double(++done) / surface.size());
        }
    });
}

}  // namespace firn::bake
