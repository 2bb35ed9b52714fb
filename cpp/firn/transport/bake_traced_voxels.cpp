#include "firn/transport/bake_traced_voxels.h"

#include <algorithm>
#include <atomic>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/bake_thin_snow.h"
#include "firn/transport/baked_grids.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/light_tracing.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/pooled_estimates.h"
#include "firn/transport/traced_source.h"

namespace firn::bake {

namespace {

// At most this many paths in all: beyond it, fewer per voxel (a bake must not grow into a hang).
constexpr double kMaxTracedPaths = 2e7;

// Paths per traced voxel: the preset's, fewer when the paths would cost more than kMaxTracedSteps in all
// (64 at least), or 0 (none traced: the diffusion takes them) when even 64 would. The cost per path is measured
// on a few voxels first: thin voxels in a large cloud of thin snow still see light that scattered thousands of
// times, lumps of 20 optical depths per voxel take thousands of tracking steps per path (their shadow rays
// included), and a bake must not grow into a hang. A path costs its tracking steps plus kStepsPerPath for
// its start (the gathering's fixed cost: 1.5 us per path on ball_half_tau, at 16 M steps per processor
// second, as spray_dense's long paths). The budget: a ski spray's frame (774 traced voxels of lumps, 2585
// steps per path; docs/spray.md) takes 99 paths per voxel, 13.0 % mean error per block (24.9 %, worst
// +210 %, with 25 paths per voxel: hence 64 at least; 11.3 % with 256). Where all the paths cost little, more
// of them (up to the preset's cheapTracedSamples, while they cost at most kCheapTracedSteps): a small object's
// few traced voxels show their estimates' noise, and 1024 paths each cost it well under a processor second
// (bench/bake_suite.py --seeds 4 at FINAL, 256 -> 1024 paths: ball_thin 4.6 -> 4.0 %, ball_thin_forward 9.8 ->
// 7.0 %, ball_rgb 8.8 -> 8.0 %, ball_forward 16.4 -> 15.1 %, spray_lumps 12.5 -> 10.2 %, the tracing 0.05 -> 0.2,
// 0.2 -> 0.9 processor s; spray_dense and ball_half_tau, over the budget at 256 already, as they were). Short
// paths (at most kShortPathSteps: thin snow in a small object, 34-42 steps on ball_half_tau and a light dusting)
// may cost up to kShortTracedSteps: a light dusting's 1728 voxels at 1024 paths for the fit by direction
// (tracedSourceByDirection; its estimates at 256 paths are too noisy; the trace 0.56 -> 2.47 processor s), and
// ball_half_tau's 2512 at g 0.3 gain too (1.9 -> 1.5 %, the trace 1.04 -> 2.23 s). Long ones keep kCheapTracedSteps:
// the car's 3 traced voxels in 2.7 M voxels of thick snow (thousands of steps per path) took 0.84 -> 2.94 processor s
// at kShortTracedSteps, for three voxels.
constexpr double kStepsPerPath = 20.0;                               // a path's start, in tracking steps
constexpr double kCheapTracedSteps = 2e7;                            // about 1.2 processor seconds
constexpr double kShortPathSteps = 1000.0, kShortTracedSteps = 8e7;  // about 5 processor seconds
// Forward scattering snow (g >= kMinLightTracedG) is light traced at what gathering its voxels would cost
// (kLightTracedShare of the pilot's steps: light tracing's sums cost more per counted step, 1.3-1.6x in processor
// seconds at the same count) where that affords light tracing's least photons (planLightTracing), else gathered:
// a gathered path's next-event estimates weigh the sun by Henyey-Greenstein, which at g 0.85 spans 2000x as the
// path turns, while photons scatter by sampling it and add at every collision, shared by the voxels they cross.
// bench/bake_suite.py --seeds 4, mean error per block and the whole bake's processor seconds (docs/benchmarks.md,
// trace-noise): ball_thin_forward 6.6 -> 5.5 % (0.24 -> 0.14 s), spray_lumps 10.0 -> 7.6 % (2.45 -> 2.31 s),
// ball_issue 10.5 -> 10.4 % (0.63 -> 0.49 s), slab_thin_forward 10.0 -> 10.0 % (2.8 -> 2.8-3.2 s, the render's
// spread across seeds 8.7 -> 4.2 %, worst block +73 -> +41 %); at g 0.5 ball_thin read 4.0 -> 4.2 % (the gate).
// Not where a voxel is thicker than kMaxLightTracedTau: spray_dense (voxels up to optical depth 20, gathered where
// cameras see them) light traced read -17 % against -6 % seen against the light, and with only its voxels of
// optical depth 2 or less light traced +7.2 % against +4.9 % across it; spray_lumps' (up to 6) gained nothing from
// being gathered where seen (visible-source: 10.1 -> 10.0 %).
constexpr double kMinLightTracedG = 0.8, kLightTracedShare = 0.75, kMaxLightTracedTau = 10.0;

// Where the plan holds the preset's paths, the voxels the renderer draws (drawnByRenderer) take twice as many, up to
// the preset's cheapTracedSamples, while those extra paths cost at most kDrawnExtraSteps (priced apart from the
// budget, which the faces then share as before). With Cycles scattering the thin traced snow itself (firn_scatter)
// the lumps' thicker voxels are what it draws, and their 256-path estimates read the lit side dark (the lobe-pair fit
// on noisy moments, docs/benchmarks.md dense-lumps): spray_dense over seeds 0-3, mixed render 11.28 -> 10.31 %, baked
// 16.58 -> 15.75 %, the lit cores -15.6 -> -12.9 %, the trace 3.2 -> 5.1 processor s (its 237 drawn voxels' extra
// 8.1e7 pilot steps); the scattered voxels' paths buy nothing there (docs/benchmarks.md, spray-light).
constexpr int kDrawnPathShare = 2;
constexpr double kDrawnExtraSteps = 1e8;  // about 2.4 processor seconds on spray_dense's long paths

// Whether the renderer draws the voxel's baked emission rather than scattering in it where the bake traces it
// (scatterMask: sigma_t h under BakedGrids::kScatterOpticalDepth scatters).
bool drawnByRenderer(const Medium &medium, Medium::Accessor &density, const openvdb::Coord &voxel) {
    return !(voxelOpticalDepth(medium, density, voxel) < BakedGrids::kScatterOpticalDepth);
}

// A pilot's paths per item it measures, and how many items it measures (pilotStepsPerPath).
constexpr int kPilotSamples = 4;
constexpr std::size_t kPilots = 64;

// Tracking steps per path, a path's start (kStepsPerPath) included, measured on kPilotSamples paths of each of
// `pilots` items spread over `count` (item count * k / pilots: with fewer items than pilots, one that repeats counts
// again), `steps(i)` item i's paths' steps, summed in order (the same price every run); infinite as soon as the sum
// exceeds `most` per path (a pilot dearer than what it prices stops). How the traced voxels (planGathering) and their
// faces (faceStepsPerPath) are priced.
template <class Steps>
double pilotStepsPerPath(std::size_t count, std::size_t pilots, const Steps &steps,
                         double most = std::numeric_limits<double>::infinity()) {
    if (pilots == 0) return 0.0;
    const double paths = double(pilots) * kPilotSamples;
    double sum = 0.0, last = 0.0;  // last: the item before's steps (fewer items than pilots repeat theirs)
    for (std::size_t k = 0; k < pilots; ++k) {
        const std::size_t i = count * k / pilots;
        if (k == 0 || i != count * (k - 1) / pilots) last = double(steps(i)) + kStepsPerPath * kPilotSamples;
        sum += last;
        if (sum > most * paths) return std::numeric_limits<double>::infinity();
    }
    return sum / paths;
}

}  // namespace

namespace {

// How a traced voxel is gathered: where cameras see it (gatheredWhereSeen), else spread over it.
Gathering gathering(const Medium &medium, Medium::Accessor &density, const openvdb::Coord &voxel) {
    return gatheredWhereSeen(medium, density, voxel) ? Gathering::WhereSeen : Gathering::Spread;
}

}  // namespace

namespace {

// The tracking steps a small scene's traced voxels may take in all (Preset::smallSceneTracedSteps, kSmallSceneVoxels).
double smallSceneSteps(const Scene &scene, const Preset &preset) {
    const double snowVoxels = double(scene.medium->density().activeVoxelCount());
    return preset.smallSceneTracedSteps * std::min(1.0, kSmallSceneVoxels / std::max(snowVoxels, 1.0));
}

}  // namespace

GatheringPlan planGathering(const Scene &scene, const Preset &preset, const std::vector<openvdb::Coord> &voxels,
                            std::uint64_t seed, SmallSceneWork smallScene) {
    constexpr int kMinSamples = 64;
    if (voxels.empty()) return {};
    const MonteCarloReference reference(scene);
    Medium::Accessor density = scene.medium->accessor();
    const double budget = kMaxTracedSteps / (double(voxels.size()) * kMinSamples);  // per path, at the least
    const double perPath = pilotStepsPerPath(voxels.size(), kPilots, [&](std::size_t v) {
        // As traceSources gathers it: where cameras see it, those points' draws counted too.
        const Gathering how = gathering(*scene.medium, density, voxels[v]);
        return reference.sourceIn(voxels[v], kPilotSamples, seed, v, how).steps;
    }, budget);
    if (perPath > budget) return {};  // too costly
    const int affordable = int(std::min(kMaxTracedPaths, kMaxTracedSteps / perPath) / double(voxels.size()));
    if (affordable < kMinSamples) return {};
    const double allVoxels = perPath * double(voxels.size());  // one path of each voxel
    // The preset's paths, doubled while they cost little (up to its cheap paths), then as many as a small scene's
    // traced work affords (up to kMostTracedShare times those; the Kronecker sequence stratifies any count).
    int samples = std::min(affordable, preset.tracedSamples);
    const double cheap = perPath <= kShortPathSteps ? kShortTracedSteps : kCheapTracedSteps;
    while (2 * samples <= preset.cheapTracedSamples && allVoxels * 2.0 * samples <= cheap) samples *= 2;
    const int doubled = samples;
    const double small = smallScene == SmallSceneWork::Available ? smallSceneSteps(scene, preset) : 0.0;
    const double most = double(kMostTracedShare) * preset.cheapTracedSamples;
    if (small > 0.0) samples = std::max(samples, int(std::min(small / allVoxels, most)));
    int drawnPaths = samples;  // twice the preset's where those hold (kDrawnPathShare), as many as the raise's above
    if (doubled >= preset.tracedSamples && kDrawnPathShare * doubled <= preset.cheapTracedSamples) {
        const auto drawn = std::count_if(voxels.begin(), voxels.end(), [&](const openvdb::Coord &c) {
            return drawnByRenderer(*scene.medium, density, c);
        });
        if (perPath * (kDrawnPathShare - 1) * doubled * double(drawn) <= kDrawnExtraSteps)
            drawnPaths = std::max(samples, kDrawnPathShare * doubled);
    }
    // The lit faces' ratio to the faces as when these took half the voxel's paths and the lit faces kLitFacePaths.
    constexpr int kLitFaceMultiple = 2 * kFacePathsPerVoxelPath;
    return {samples, allVoxels * samples, drawnPaths,
            std::min(kFacePathsPerVoxelPath * doubled, preset.cheapTracedSamples),
            std::min(kLitFaceMultiple * kLitFacePaths, preset.cheapTracedSamples),
            small - allVoxels * (samples - doubled)};
}

namespace {

// The traced voxels' sources from their estimates (`estimate(v)`: voxel v's, called in parallel, gathered by
// `reference`).
template <class Estimate>
MonteCarloVoxels tracedVoxels(const MonteCarloReference &reference, const std::vector<openvdb::Coord> &voxels,
                              const Estimate &estimate, const SubProgress &progress) {
    MonteCarloVoxels out;
    out.source.resize(voxels.size());
    const Medium &medium = *reference.scene().medium;
    const double g = medium.optics().g;
    const SourceDirections &directions = reference.directions();
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 4), [&](const auto &range) {
        Medium::Accessor density = medium.accessor();
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
            progress.throwIfCancelled();  // each voxel's paths (a chunk may hold many voxels)
            out.source[v] = fittedByDirection(medium, density, voxels[v])
                                ? tracedSourceByDirection(estimate(v), directions,
                                                          visibilityFrom(medium, marcher, voxels[v], directions), g)
                                : tracedSourceByMoments(estimate(v), g);
        }
        progress.report(double(done += range.size()) / voxels.size());
    });
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> index(*out.index);
    for (std::size_t v = 0; v < voxels.size(); ++v)
        index.setValue(voxels[v], std::int32_t(v)), out.box.expand(voxels[v]);
    return out;
}

}  // namespace

// The source function of the given voxels by brute force (MonteCarloReference::sourceIn), `samples` each.
MonteCarloVoxels traceSources(const Scene &scene, const std::vector<openvdb::Coord> &voxels, int samples,
                              std::uint64_t seed, const SubProgress &progress, int drawnSamples) {
    const MonteCarloReference reference(scene);
    const Medium &medium = *scene.medium;
    return tracedVoxels(reference, voxels, [&](std::size_t v) {
            Medium::Accessor density = medium.accessor();
            const int paths = drawnSamples > 0 && drawnByRenderer(medium, density, voxels[v]) ? drawnSamples : samples;
            return reference.sourceIn(voxels[v], paths, seed, v, gathering(medium, density, voxels[v]), progress);
        }, progress);
}

namespace {

// A traced layer's voxels thicker than this gather their faces open to air on one side (addFaceSources); thinner
// ones a camera sees through, as kTracedOpticalDepth has it. Kept equal to kTracedOpticalDepth: the layer's voxels
// that `thin` holds (marked out of the layer) are thinner and need none.
constexpr double kMinLayerFaceTau = 1.5;
// ... and at least this many paths per face, else none: at 128 (slab_thin at FINAL: 512 / 4) the faces' noise ate
// what they mended (one seed 6.2 %, as without them), at DRAFT's 64 8.2 % against 6.5 % without (docs/benchmarks.md,
// slab-thin).
constexpr int kMinLayerFacePaths = 256;

// A face job: voxel, face (0..5).
using FaceJob = std::pair<std::size_t, int>;

double greyMean(const Rgb &c) { return (c.x + c.y + c.z) / 3.0; }

// A face is lit where it faces a light and its collisions take that light's beam: the beams scattered once are at
// least this share of their source (spray_dense, 4 seeds: 0.05 gave the lit cores most, 0.1-0.15 read as it
// overall; 0 lit the shadowed faces that face the sun: docs/benchmarks.md, spray-lit-faces).
constexpr double kLitFaceBeamShare = 0.05;

// Whether face f (-x, +x, -y, +y, -z, +z) of the voxel centred at `centre`, its collisions' source `all`, is lit.
bool litFace(const Scene &scene, const glm::dvec3 &centre, int f, const SourceEstimate &all) {
    if (!(greyMean(all.beamL0) > kLitFaceBeamShare * greyMean(all.l0))) return false;
    for (std::size_t b = 0; b < beamCount(scene); ++b)
        if ((f % 2 ? 1.0 : -1.0) * towardsBeam(scene, b, centre)[f / 2] > 0.0) return true;
    return false;
}

// Where a face lies in a flat layer: at least this many of its voxel's 8 neighbours in the face's plane hold the
// same face, their density within kPooledDensityRatio (a layer's rim has 5). Elsewhere (a lump's thin part,
// spray_dense: 20.2 % over 4 seeds with all its faces so, against 19.2 %) the face's air neighbour carries its own
// share of the collisions' source, fitted to its moments, and the voxel keeps its own value (addFaceSources).
constexpr int kMinLayerNeighbours = 5;

// The estimates' source towards each direction pooled over the face's layer neighbours (kMinLayerNeighbours),
// scaled to each one's own mean, as light tracing pools a flat layer's (pooled_estimates.h): 64 paths per face,
// split by the hat, hold about 20 paths' worth each. `inLayer`: per job, whether its face lies in a flat layer.
std::vector<FaceEstimate> pooledOverFace(const Medium &medium, const MonteCarloVoxels &traced,
                                         const std::vector<openvdb::Coord> &voxels, const std::vector<FaceJob> &jobs,
                                         const std::vector<FaceEstimate> &estimates, std::vector<bool> &inLayer) {
    inLayer.assign(jobs.size(), false);
    std::vector<int> jobAt(voxels.size() * 6, -1);
    for (std::size_t j = 0; j < jobs.size(); ++j) jobAt[jobs[j].first * 6 + jobs[j].second] = int(j);
    Medium::Accessor density = medium.accessor();
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*traced.index);
    std::vector<FaceEstimate> out = estimates;
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        const auto [v, f] = jobs[j];
        const double rho = density.getValue(voxels[v]);
        FaceEstimate sum;
        int neighbours = -1;  // not itself
        for (int da = -1; da <= 1; ++da)
            for (int db = -1; db <= 1; ++db) {
                openvdb::Coord n = voxels[v];
                n[(f / 2 + 1) % 3] += da, n[(f / 2 + 2) % 3] += db;
                const std::int32_t t = index.getValue(n);
                const int k = t < 0 ? -1 : jobAt[std::size_t(t) * 6 + f];
                if (k < 0 || !(std::max(density.getValue(n) / rho, rho / density.getValue(n)) <= kPooledDensityRatio))
                    continue;
                sum.carried += estimates[k].carried, sum.shown += estimates[k].shown, ++neighbours;
            }
        if (!(inLayer[j] = neighbours >= kMinLayerNeighbours)) continue;
        const auto pool = [](SourceEstimate &own, const SourceEstimate &pooled) {
            if (!(greyMean(pooled.l0) > 0.0)) return;
            const double scale = greyMean(own.l0) / greyMean(pooled.l0);
            for (int k = 0; k < kSourceDirections; ++k) own.toward[k] = pooled.toward[k] * scale;
        };
        pool(out[j].carried, sum.carried), pool(out[j].shown, sum.shown);
    }
    return out;
}

// wa a + wb b, wa + wb = 1 (steps summed).
SourceEstimate blend(const SourceEstimate &a, double wa, const SourceEstimate &b, double wb) {
    SourceEstimate out;
    out.l0 = wa * a.l0 + wb * b.l0, out.l1 = wa * a.l1 + wb * b.l1;
    out.beamL0 = wa * a.beamL0 + wb * b.beamL0, out.beamL1 = wa * a.beamL1 + wb * b.beamL1;
    out.second = wa * a.second + wb * b.second;
    for (int i = 0; i < 3; ++i) out.third[i] = wa * a.third[i] + wb * b.third[i];
    for (int k = 0; k < kSourceDirections; ++k) out.toward[k] = wa * a.toward[k] + wb * b.toward[k];
    out.steps = a.steps + b.steps;
    return out;
}

// The source over all of a face's collisions, carried and shown together.
SourceEstimate whole(const FaceEstimate &S) { return blend(S.carried, 1.0 - S.shownShare, S.shown, S.shownShare); }

// Two estimates of one face from `na` and `nb` points as one of na + nb: each part weighted by its hat's weight
// (faceSourceIn: a point's weight splits between the parts, shownShare the voxel's mean share).
FaceEstimate pooled(const FaceEstimate &a, int na, const FaceEstimate &b, int nb) {
    const auto part = [](const SourceEstimate &x, double wx, const SourceEstimate &y, double wy) {
        return wx + wy > 0.0 ? blend(x, wx / (wx + wy), y, wy / (wx + wy)) : blend(x, 1.0, y, 0.0);
    };
    const double sa = na * a.shownShare, sb = nb * b.shownShare;
    return {part(a.carried, na - sa, b.carried, nb - sb), part(a.shown, sa, b.shown, sb), (sa + sb) / (na + nb)};
}

// The lit faces' estimates (litFace) from `wanted` paths (litFacePaths): `paths` more each, from a stream of their own,
// pooled with those from the faces' `paths`.
void moreOnLitFaces(const Scene &scene, const MonteCarloReference &reference, const std::vector<openvdb::Coord> &voxels,
                    const std::vector<FaceJob> &jobs, int paths, int wanted, std::uint64_t seed,
                    const SubProgress &progress, std::vector<FaceEstimate> &estimates) {
    const Medium &medium = *scene.medium;
    std::vector<std::size_t> lit;
    double litSteps = 0.0;
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        const auto [v, f] = jobs[j];
        if (!litFace(scene, medium.voxelCentre(voxels[v]), f, whole(estimates[j]))) continue;
        lit.push_back(j);
        litSteps += double(estimates[j].carried.steps);
    }
    const int extra = litFacePaths(paths, wanted, litSteps) - paths;
    if (extra <= 0) return;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lit.size(), 2), [&](const auto &range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const std::size_t j = lit[i];
            const auto [v, f] = jobs[j];
            const FaceEstimate more =
                reference.faceSourceIn(voxels[v], f, extra, seed, voxels.size() * (7 + f) + v, progress);
            estimates[j] = pooled(estimates[j], paths, more, extra);
        }
    });
}

// The voxel's own value from what it shows the cameras of its open faces (jobs [first, last), all the voxel's):
// towards each direction, what it shows the face that direction leaves through most (along its outward normal),
// the moments the faces' mean, fitted by direction (`visibility`: visibilityFrom the voxel).
Source shownByFaces(const SourceDirections &directions, const DirectionWeights &visibility, double g,
                    const std::vector<FaceJob> &jobs, const std::vector<FaceEstimate> &estimates, std::size_t first,
                    std::size_t last) {
    SourceEstimate S;
    for (std::size_t j = first; j < last; ++j) S += estimates[j].shown;
    const double n = double(last - first);
    S.l0 /= n, S.l1 /= n, S.beamL0 /= n, S.beamL1 /= n, S.second /= n;
    for (glm::dmat3 &t : S.third) t /= n;
    for (double &t : S.toward) t /= n;
    for (int k = 0; k < kSourceDirections; ++k) {
        double nearest = 0.0;
        for (std::size_t j = first; j < last; ++j) {
            const int f = jobs[j].second;
            const double out = (f % 2 ? 1.0 : -1.0) * directions[k][f / 2];
            if (out > nearest) nearest = out, S.toward[k] = estimates[j].shown.toward[k];
        }
    }
    return tracedSourceByDirection(S, directions, visibility, g);
}

// Whether a voxel's value is what its faces show (shownByFaces), not its mean: some face lies in a flat layer and each
// other face is one-sided, its opposite closed (a layer's rim voxel, its side faces). The rim's side faces turned the
// rim voxel to its mean, 46 % brighter than it shows below at sigma_t h 15: the 16 x 16 x 1 layer from below 13.1 ->
// 11.3 %, 6 x 6 x 1 21.2 -> 18.8 % (docs/benchmarks.md, float-bisect 2). A lump's voxel (no face in a flat layer)
// keeps its mean.
bool showsItsFaces(unsigned open, const std::vector<FaceJob> &jobs, const std::vector<bool> &inLayer,
                   std::size_t first, std::size_t last) {
    bool anyInLayer = false;
    for (std::size_t j = first; j < last; ++j) {
        if (inLayer[j]) {
            anyInLayer = true;
        } else if (open >> (jobs[j].second ^ 1) & 1u) {
            return false;  // open on both sides, not in a flat layer
        }
    }
    return anyInLayer;
}

}  // namespace

namespace {

// The faces of traced voxel `voxel` open to air (bit f for face f: -x, +x, -y, +y, -z, +z): an unknown's (`i`, its
// index in `topo`) from the topology, but not one toward a traced voxel (a lump's fringe: that neighbour takes its own
// value, so no air carries the face; spray_dense spent 278 of its unknowns' 507 faces so); a fringe voxel's (under 5
// optical depths on a thicker one, kFringeOpticalDepth: part of the density ramp, not an unknown, yet traced, and
// thicker than kMaxDirectionFitTau) where its neighbour holds no snow and no occluder lies between the two centres, as
// the topology's isAirFace. The air across each of its faces carries that face's source (faceCarried), the outer
// face's (away from the thick voxel) too, two voxels from the surface unknowns. No fringe's lit bits are read
// (litFacesToward: unknowns).
unsigned airFaces(const Medium &medium, const Occluders &occluders, const SnowTopology &topo,
                  Medium::Accessor &density, TracedIndex &tracedIndex, const openvdb::Coord &voxel, std::int32_t i) {
    unsigned open = 0;
    if (i >= 0) {
        for (int f = 0; f < 6; ++f) {
            const bool towardTraced = tracedIndex.getValue(voxel + faceStep(f)) >= 0;
            open |= unsigned(topo.isAirFace(std::size_t(i), f) && !towardTraced) << f;
        }
        return open;
    }
    for (int f = 0; f < 6; ++f)
        open |= unsigned(!(density.getValue(voxel + faceStep(f)) > 0.0f) && !occluderAcross(medium, occluders, voxel, f))
                << f;
    return open;
}

// Tracking steps a face's path takes, measured on a few of the faces first (pilotStepsPerPath over `jobs`, as
// planGathering's on the voxels; its own stream, so the faces' estimates stay as without it). A lump's face
// gathers where its cameras collide, in its first optical depths, and those paths leave sooner than the voxel's,
// which start throughout it: spray_dense's faces take 662-665 steps per path (this pilot reads 668-729, seeds 0-3)
// against its voxels' pilot's 1336; priced at the voxels' the budget left held 144 of their 512 paths, at their own
// 276-304 (docs/benchmarks.md, face-share, face-pilot).
double faceStepsPerPath(const MonteCarloReference &reference, const std::vector<openvdb::Coord> &voxels,
                        const std::vector<FaceJob> &jobs, std::uint64_t seed) {
    return pilotStepsPerPath(jobs.size(), std::min(kPilots, jobs.size()), [&](std::size_t j) {
        const auto [v, f] = jobs[j];
        const FaceEstimate pilot =
            reference.faceSourceIn(voxels[v], f, kPilotSamples, seed, voxels.size() * (13 + f) + v);
        return pilot.carried.steps + pilot.shown.steps;
    });
}

}  // namespace

FaceGathering gatheredVoxelFaces(const GatheringPlan &plan) {
    const int fewest = std::min(plan.facePaths, std::max(64, plan.paths / 4));  // a raised plan's quarter may pass them
    return {plan.facePaths, fewest, kMaxTracedSteps - plan.steps + plan.smallSceneSteps, {}, plan.litFacePaths};
}

// A lump's lit face (litFace) is what the air beside it carries towards the cameras that see the lump's sunlit side,
// through the lobe pair fitted to its moments (tracedSourceByMoments), and a fit on noisy moments reads low: along
// the lit faces' normals against an independent truth, spray_dense's 120 lit faces read 0.919 at 128 paths and 0.967
// at 1024 (docs/benchmarks.md, face-lobes), 1 - b - c / N with c = 0.048 / (1/128 - 1/1024) = 7.0 paths (the
// converged b 2.6 %: the pair's shape, which paths do not mend). kLitFacePaths holds c / N under the suite
// reference's 2 % noise per block; the extra paths go where the fit's bias shows (the shadowed faces' fits read
// within 3 % converged, spray-cores), priced apart from kMaxTracedSteps as the drawn voxels' are (planGathering), up
// to the preset's cheapTracedSamples (DRAFT's faces keep theirs: a ski spray's frame bakes as before).
int litFacePaths(int paths, int wanted, double litSteps) {
    if (wanted <= paths || !(litSteps > 0.0)) return std::max(paths, wanted);
    const double extraPerPath = litSteps / paths;  // the lit faces' steps per path beyond `paths`, all of them
    return paths + int(std::min(double(wanted - paths), kLitFaceExtraSteps / extraPerPath));
}

FaceGathering layerFaces(const Scene &scene, const Preset &preset, const std::vector<openvdb::Coord> &voxels,
                         std::vector<bool> inLayer, std::uint64_t seed) {
    const GatheringPlan plan = planGathering(scene, preset, voxels, seed, SmallSceneWork::TakenByLightTracing);
    if (plan.paths < kMinLayerFacePaths) return {};
    return {plan.paths, plan.paths, kMaxTracedSteps - kWholePieceTracedSteps, std::move(inLayer)};
}

// A floating layer one voxel thick is seen from each side in that side's first optical depth, which its voxels' mean
// source (the one both its air neighbours carried) is not: at sigma_t h 15, lit from above, the top views read -34 %
// (docs/bake.md, Method 3). Its gathered voxels thicker than kMaxDirectionFitTau gather, for each face open to air,
// where that face's cameras collide (faceSourceIn); so do a lump's, one-sided too (a camera sees a face's first optical
// depth, not the voxel's mean): spray_dense over 4 seeds 19.1 -> 17.9 % per block (docs/benchmarks.md,
// spray-lump-faces). In a flat layer (kMinLayerNeighbours) the light there is split by the trilinear hat between what
// the air neighbour across the face carries (faceCarried) and what the voxel's own value shows those cameras
// (FaceSources::shown; towards each direction the face its cameras look through), each fitted by direction, the
// estimates' directions pooled over the layer (pooledOverFace); the voxel's mean stays what its other neighbours carry
// (a layer's rim seen edge-on). The 16 x 16 x 1 layer at sigma_t h 15 (bench/snow_on_ground_bench.py --float): from
// above 33.3 % per block (main before float-voxel) -> 9.1 % (faces carried their whole collisions' source, the voxel
// its mean) -> 8.8 %, from below 52.4 -> 19.2 -> 10.7 %: seen from below the mean is 46 % brighter than what the voxel
// shows there (the sun-lit top's light, forward), from above 32 % darker (docs/benchmarks.md, float-under; at sigma_t h
// 3 from above 6.5 -> 8.0 %). A face takes `how.paths` where they fit `how.budget` (what the gathering leaves of
// kMaxTracedSteps) at the faces' own steps per path (faceStepsPerPath), else as many as fit down to `how.fewestPaths`
// (a quarter of the voxel's, 64 at least: spray_dense's 471 faces at 128 paths; at 64 18.7 %, their noise ate most of
// what they mend; halved at once, its 507 faces with its lumps traced fell to 64 for a cost 3 % over: 21.1 % against
// 17.5 % at 124); none where even those would cost more. A traced layer light
// traced whole (how.inLayer) is seen so too, from one side: its voxels of sigma_t h > kMinLayerFaceTau gather each
// face open to air, at the gathering's paths per voxel (the light tracing gave them none; a quarter of them, 128, left
// a 5.9 % spread per block), within what the light tracing leaves of kMaxTracedSteps (its pilot's estimate for
// slab_thin's 1440 faces is 3.5e7 steps at seeds 0-1 and 6.6e7 at seed 2): slab_thin 6.2 -> 3.9 % per block, from
// below (0, -60) +8 -> +3 % (docs/benchmarks.md, slab-thin).
FacesTraced addFaceSources(const Scene &scene, const SnowTopology &topo, const std::vector<openvdb::Coord> &voxels,
                           const FaceGathering &how, std::uint64_t seed, const SubProgress &progress,
                           MonteCarloVoxels &traced) {
    if (how.paths == 0) return {};  // not affordable
    const Medium &medium = *scene.medium;
    Medium::Accessor density = medium.accessor();
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
    TracedIndex tracedIndex(traced);
    traced.facesAt.assign(voxels.size(), -1);
    std::vector<FaceJob> jobs;  // by voxel, the unknowns' first
    const auto addFaces = [&](bool unknowns) {
        for (std::size_t v = 0; v < voxels.size(); ++v) {
            // A traced layer's voxels are all unknowns: under kTracedLayerOpticalDepth, it has no fringe.
            const std::int32_t i = index.getValue(voxels[v]);
            if ((i >= 0) != unknowns) continue;
            const double tau = voxelOpticalDepth(medium, density, voxels[v]);
            FaceSources faces;
            if (how.inLayer.empty() ? tau > kMaxDirectionFitTau : how.inLayer[v] && tau > kMinLayerFaceTau)
                faces.open = airFaces(medium, *scene.occluders, topo, density, tracedIndex, voxels[v], i);
            if (!faces.open) continue;
            traced.facesAt[v] = std::int32_t(traced.faces.size());
            traced.faces.push_back(faces);
            for (int f = 0; f < 6; ++f)
                if (faces.open >> f & 1u) jobs.emplace_back(v, f);
        }
    };
    addFaces(true);
    const std::size_t unknownsJobs = jobs.size(), unknownsFaces = traced.faces.size();
    addFaces(false);
    const MonteCarloReference reference(scene);
    const double stepsPerPath = faceStepsPerPath(reference, voxels, jobs, seed);
    const auto cost = [&](int paths) { return stepsPerPath * paths * double(jobs.size()); };
    if (cost(how.fewestPaths) > how.budget) {  // the fringes' faces only where all fit: they never cost the unknowns'
        jobs.resize(unknownsJobs), traced.faces.resize(unknownsFaces);
        for (std::int32_t &at : traced.facesAt)
            if (at >= std::int32_t(unknownsFaces)) at = -1;
    }
    int samples = how.paths;
    if (cost(samples) > how.budget)  // as many as fit (no voxel or step: the budget's sign decides below)
        samples = std::max(how.fewestPaths, int(std::clamp(how.budget / cost(1), 0.0, double(samples))));
    if (cost(samples) > how.budget) {
        traced.facesAt.clear(), traced.faces.clear();
        return {0, 0, stepsPerPath};
    }
    std::vector<FaceEstimate> estimates(jobs.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, jobs.size(), 4), [&](const auto &range) {
        for (std::size_t j = range.begin(); j != range.end(); ++j) {
            const auto [v, f] = jobs[j];
            estimates[j] = reference.faceSourceIn(voxels[v], f, samples, seed, voxels.size() * (1 + f) + v, progress);
        }
    });
    if (how.litPaths > samples)
        moreOnLitFaces(scene, reference, voxels, jobs, samples, how.litPaths, seed, progress, estimates);
    std::vector<bool> inLayer;
    estimates = pooledOverFace(medium, traced, voxels, jobs, estimates, inLayer);
    const SourceDirections &directions = reference.directions();
    const double g = medium.optics().g;
    std::vector<std::size_t> firstJob;  // per voxel with faces, its first job
    for (std::size_t j = 0; j < jobs.size(); ++j)
        if (j == 0 || jobs[j - 1].first != jobs[j].first) firstJob.push_back(j);
    firstJob.push_back(jobs.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, firstJob.size() - 1, 8), [&](const auto &range) {
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const std::size_t first = firstJob[i], last = firstJob[i + 1], v = jobs[first].first;
            const DirectionWeights visibility = visibilityFrom(medium, marcher, voxels[v], directions);
            FaceSources &faces = traced.faces[traced.facesAt[v]];
            for (std::size_t j = first; j < last; ++j) {
                // The air carries what its hat holds of the collisions, the shallow part cameras cross in the ramp,
                // outside a flat layer too: the whole collisions' source (the voxel's share, its own value's, in it)
                // read grazing rays bright, lit ones +17 % (spray_dense over seeds 0-7 13.60 -> 13.25 % per block;
                // docs/benchmarks.md, spray-rims 2026-12-04).
                const SourceEstimate &carried = estimates[j].carried;
                faces.source[jobs[j].second] = inLayer[j]
                                                   ? tracedSourceByDirection(carried, directions, visibility, g)
                                                   : tracedSourceByMoments(carried, g);
                const SourceEstimate all = whole(estimates[j]);
                faces.lit |= unsigned(litFace(scene, medium.voxelCentre(voxels[v]), jobs[j].second, all))
                             << jobs[j].second;
            }
            faces.shown = showsItsFaces(faces.open, jobs, inLayer, first, last)
                              ? shownByFaces(directions, visibility, g, jobs, estimates, first, last)
                              : traced.source[v];
        }
    });
    return {samples, jobs.size(), stepsPerPath};
}

// The voxels whose gathering costs more than the budget (planGathering: no paths), by light tracing within it
// (light_tracing.h); none where even that costs too much (a cloud of lumps inside thick snow: photons
// scatter thousands of times there), or with lamps (their emission is not sampled: planLightTracing).
MonteCarloVoxels lightTraceSources(const Scene &scene, const std::vector<openvdb::Coord> &voxels, std::uint64_t seed,
                                   const SubProgress &progress, BakeStats &stats, double budget, double share) {
    const MonteCarloReference reference(scene);
    const LightTracingPlan plan = planLightTracing(reference, voxels, budget, seed, share);
    if (plan.photons == 0) return MonteCarloVoxels{};
    const std::vector<SourceEstimate> estimates = lightTracedSources(reference, voxels, plan, seed, progress);
    stats.photons = plan.photons, stats.lightTracedVoxels = voxels.size(), stats.lightTracingBytes = plan.sumsBytes;
    // The fit alone left: the photons have run the progress to its end.
    return tracedVoxels(reference, voxels, [&](std::size_t v) { return estimates[v]; }, SubProgress(nullptr, 0.0, 1.0));
}

// Forward scattering snow at what gathering it costs (kMinLightTracedG): light traced within kLightTracedShare of
// the gathering's steps, unless some voxel is thicker than kMaxLightTracedTau (light tracing tallies a voxel's
// mean, not what cameras see of a thick one). None (empty) there, for broader scattering, without a gathering plan,
// or where light tracing is not affordable so.
MonteCarloVoxels lightTracedAtGatheringCost(const Scene &scene, const std::vector<openvdb::Coord> &voxels,
                                            const GatheringPlan &plan, std::uint64_t seed, const SubProgress &progress,
                                            BakeStats &stats) {
    if (plan.paths <= 0 || scene.medium->optics().g < kMinLightTracedG) return {};
    Medium::Accessor density = scene.medium->accessor();
    for (const openvdb::Coord &c : voxels)
        if (voxelOpticalDepth(*scene.medium, density, c) > kMaxLightTracedTau) return {};
    return lightTraceSources(scene, voxels, seed, progress, stats, kLightTracedShare * plan.steps);
}

}  // namespace firn::bake
