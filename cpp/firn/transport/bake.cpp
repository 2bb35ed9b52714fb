#include "firn/transport/bake.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <tuple>

#include <openvdb/tools/Diagnostics.h>
#include <tbb/task_arena.h>

#include "firn/transport/bake_diffusion_system.h"
#include "firn/transport/bake_grid_values.h"
#include "firn/transport/bake_preset.h"
#include "firn/transport/bake_snow_irradiance.h"
#include "firn/transport/bake_source_function.h"
#include "firn/transport/bake_surface_light.h"
#include "firn/transport/bake_thin_snow.h"
#include "firn/transport/bake_traced_voxels.h"
#include "firn/transport/bounce_tail.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/multigrid.h"
#include "firn/transport/skin_ring.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/error.h"
#include "firn/util/threads.h"

namespace firn {

// The bake's parts (transport/bake_*).
using bake::ChannelStorage, bake::ChannelSystem, bake::EdgeFaceLobes, bake::GatheringPlan, bake::GridValues,
    bake::MonteCarloVoxels, bake::PeakedLobes, bake::Preset, bake::SnowIrradiance, bake::SnowLight, bake::SourceValues,
    bake::SurfaceLight, bake::SurfaceTerms, bake::TracedSnow;
using bake::addFaceSources, bake::assemble, bake::gatheredVoxelFaces, bake::gridValues, bake::layerFaces,
    bake::lightTracedAtGatheringCost, bake::lightTraceSources,
    bake::makeGrids, bake::planGathering, bake::rampPeaks, bake::referenceSurface, bake::scatterGrid,
    bake::skinRingGrowths, bake::skyShares, bake::snowIrradiance, bake::sourceFunction, bake::sourceGrid,
    bake::surfaceLight, bake::surfaceRadiance, bake::thinVoxels, bake::traceSources;
using bake::kMaxTracedSteps, bake::kSmallSceneTracedSteps, bake::kWholePieceTracedSteps;

namespace {

constexpr int kMaxSunSamples = 4096, kMaxReferenceSamples = 65536;
// IncidentLight::occluderShare from which the occluders' send-back alone is worth the gathering passes (each one
// another solve: a 160 x 160 x 30 slab's DRAFT bake 1.2 -> 2.0 processor s). A slab on a ground of albedo 0.5
// (0.10) gains 3-4 % on its sides, nothing on top; a pile of lumps on a white ground (0.38) 10 points
// (docs/benchmarks.md "send-back2").
constexpr double kSendBackWorthPasses = 0.15;

// FINAL's last solve stops at a relative residual of 1e-4, as DRAFT's: its error is far under the bake's own noise
// (the car's grids move by 0.004 % against 1e-5, where another seed moves them by 6.4 %; the suite's by at most
// 0.006 % against 0.2-80 %), and 1e-5 cost the car five V-cycles more (docs/benchmarks.md, lead-86).
Preset resolve(const BakeSettings &s) {
    constexpr double kSmall = kSmallSceneTracedSteps;  // DRAFT, a preview, keeps its counts
    Preset p = s.quality == BakeQuality::Draft ? Preset{9, 1, 1e-4, 0, 1, 64, 64, true, 0.25, 0.0}
               : s.quality == BakeQuality::Final ? Preset{9, 4, 1e-4, 0, 1, 256, 1024, true, 1.0, kSmall}
                                                 : Preset{64, 8, 1e-7, 64, 2, 1024, 1024, false, 1.0, kSmall};
    if (s.skySamples < 0 || s.sunSamples < 0 || s.referenceSamples < 0 || !(s.tolerance >= 0.0) || s.tolerance >= 1.0)
        throw InvalidArgument("bake settings: sample counts must be >= 0 and the tolerance in [0, 1)");
    // Conjugate gradients in double precision stall near 1e-15: asked for less, it iterated on a residual of
    // rounding noise until 0/0 made the whole bake NaN (fuzz seed 7179: a tolerance of 5e-324).
    if (s.tolerance > 0.0 && s.tolerance < MultigridSolver::kFinestTolerance)
        throw InvalidArgument("bake settings: the tolerance must be 0 (the quality's) or within [1e-12, 1)");
    // Each is work per surface voxel: more than these is no bake but a hang (sky rays are capped at 64 anyway).
    if (s.sunSamples > kMaxSunSamples || s.referenceSamples > kMaxReferenceSamples)
        throw InvalidArgument("bake settings: at most " + std::to_string(kMaxSunSamples) + " sun samples and " +
                              std::to_string(kMaxReferenceSamples) + " reference samples");
    if (s.sourceScale < 0 || s.sourceScale > 4)
        throw InvalidArgument("bake settings: source scale must be 0 (auto) to 4");
    if (s.skySamples) p.skySamples = s.skySamples;
    if (s.sunSamples) p.sunSamples = s.sunSamples;
    if (s.tolerance > 0.0) p.tolerance = s.tolerance;
    if (s.referenceSamples) p.referenceSamples = s.referenceSamples;
    return p;
}

// Wall-clock and processor seconds of work run on the calling thread, the processor's of this thread alone:
// isolated (tbb::this_task_arena::isolate), it takes no other work while it waits for its own loops, whose
// chunks another thread runs count where that thread's time goes.
struct ThreadSeconds {
    double wall = 0.0, cpu = 0.0;
};
template <class Work>
ThreadSeconds isolatedOnThisThread(Work &&work) {
    const auto threadCpu = [] {
        timespec t{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
        return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
    };
    const auto start = std::chrono::steady_clock::now();
    const double cpuStart = threadCpu();
    tbb::this_task_arena::isolate(std::forward<Work>(work));
    return {std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), threadCpu() - cpuStart};
}

// Wall-clock and processor time (all threads: std::clock) between laps, added to a phase's seconds.
class Stopwatch {
  public:
    explicit Stopwatch(BakeStats &stats) : stats_(stats) {}
    void lap(double BakeStats::Phases::*phase) {
        const auto now = std::chrono::steady_clock::now();
        const std::clock_t cpuNow = std::clock();
        stats_.seconds.*phase += std::chrono::duration<double>(now - last_).count();
        stats_.cpuSeconds.*phase += double(cpuNow - cpuLast_) / CLOCKS_PER_SEC;
        last_ = now, cpuLast_ = cpuNow;
    }

    // `seconds` of a phase that ran beside the laps' `within`: its wall seconds its own (they overlap
    // within's), its processor seconds moved out of within's (the last lap counted them there).
    void beside(double BakeStats::Phases::*phase, double BakeStats::Phases::*within, const ThreadSeconds &seconds) {
        stats_.seconds.*phase += seconds.wall;
        stats_.cpuSeconds.*within -= seconds.cpu;
        stats_.cpuSeconds.*phase += seconds.cpu;
    }

  private:
    BakeStats &stats_;
    std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
    std::clock_t cpuLast_ = std::clock();
};

}  // namespace

namespace {

// The finest source grids whose dense box fits Cycles' budget (kSourceBudgetBytes): a small object keeps the
// density's resolution, a street's snow gets coarser light (its dense box would not fit in memory).
int sourceScaleFor(const Medium &medium, const BakeSettings &settings) {
    if (settings.sourceScale > 0) return settings.sourceScale;
    const openvdb::Coord extent = medium.density().evalActiveVoxelBoundingBox().dim();
    const double boxVoxels =
        double(extent.x() + 6) * double(extent.y() + 6) * double(extent.z() + 6);  // + extension, ring
    int scale = 1;
    while (scale < 4 && BakedGrids::kCount * 16.0 * boxVoxels / (scale * scale * scale) > kSourceBudgetBytes) ++scale;
    return scale;
}

}  // namespace

namespace {

// Hands the heap pages that large trees and lists freed (thousands of small blocks: OpenVDB leaves, per-voxel
// lists) back to the system, so that the next phase's arrays do not come on top of them: glibc keeps them
// otherwise, and the car sample's second pass peaked 100 bytes per voxel higher than its first.
void releaseFreedMemory() {
#ifdef __GLIBC__
    malloc_trim(0);
#endif
}

// The grids read the topology's index and surface patches alone (gridValues, sourceTree): the rest (links,
// coordinates, densities, faces, neighbourhoods and shell) is freed before they are written. size() is 0 after.
void keepIndexAndPatches(SnowTopology &topo) {
    SnowTopology kept;
    kept.index = std::move(topo.index);
    kept.surfaceSlot = std::move(topo.surfaceSlot);
    kept.patches = std::move(topo.patches);
    topo = std::move(kept);
    releaseFreedMemory();
}

// The channel whose light leaving the surface voxels is split between the beams and the sky (solveBeamsApart).
constexpr int kSplitChannel = 1;
// Its solve's relative residual: 1e-2 against 1e-3 saves the car one V-cycle and moves its grids and the suite's by at
// most 0.002 % (sum |diff| / sum; another seed: 0.2-80 %; docs/benchmarks.md, lead-86).
constexpr double kBeamsApartTolerance = 1e-2;

// Of the light leaving each surface voxel (SurfaceTerms::skyLeaving), the part the sky and other snow drive, apart
// from the beams' (suns and lamps): `solver`'s system, spent on its solution phi, solved again with the beams' sources
// alone (`beams`, as assemble wrote them; the solve is linear, the rest is the sky's), in `beams` itself from phi
// scaled by the beams' share of the sources (`sources`, W; with no sky that is the solution, and no iteration runs).
// The grids read a share of it (spreadCarriedSun), so 1 % will do (kBeamsApartTolerance). One channel stands for the
// three (their albedos differ little), solved in the next channel's phi before that channel starts: no array more at
// the solves' plateau, the bake's peak memory. Returns the iterations.
int solveBeamsApart(const SnowTopology &topo, const MultigridSolver &solver, MultigridSolver::Workspace &workspace,
                    const UnwrittenVector<double> &phi, double sources, UnwrittenVector<double> &beams,
                    SurfaceTerms &surface, const SubProgress &progress) {
    UnwrittenVector<double> b = std::move(workspace.spare);  // the spent solve's right-hand side
    parallelCopy(beams, b);
    double beamSources = 0.0;  // W
    for (const double v : b) beamSources += v;
    int iterations = 0;
    if (beamSources > 0.0 && sources > 0.0) {
        for (std::size_t i = 0; i < phi.size(); ++i) beams[i] = phi[i] * (beamSources / sources);
        iterations = solver.solve(std::move(b), beams, kBeamsApartTolerance, 500, progress, &workspace).iterations;
    } else {
        std::fill(beams.begin(), beams.end(), 0.0);
        workspace.spare = std::move(b);
    }
    surface.skyLeaving = ChannelSystem::surfaceZeros(topo);
    for (std::size_t i = 0; i < topo.size(); ++i)
        if (topo.patches[i].isSurface())
            surface.skyLeaving.surface(i) =
                float(surface.escaped[i] - surface.sunEscaped[i] + surface.outConductance[i] * (phi[i] - beams[i]));
    return iterations;
}

// The relative residual that solves of passes before the last stop at: they only feed the gathering between
// surfaces, whose light is a small part of the last pass's sources (the car's: about 5 % of b), so their error
// reaches the grids at that share. On the car 1e-1 against 1e-2 takes the first pass's V-cycles 5 -> 3 and moves its
// grids' l0 by 0.010 % (sum |diff| / sum) where another seed moves it by 6.4 %; the suite's cases by at most 1/60 of
// their seed's (docs/benchmarks.md, car-pass2, lead-86). Not where the bounce tail extrapolates from the differences
// between passes (addBounceTail: up to 4 times the last bounce): those passes keep 1e-3.
constexpr double kGatheredPassTolerance = 1e-1, kExtrapolatedPassTolerance = 1e-3;

// Progress when the diffusion solves are done (REFERENCE: before path tracing the surface).
constexpr double kSolvedProgress = 0.9, kSolvedProgressReference = 0.5;

// The source function of every unknown: per pass (the later ones gather the light between snow surfaces
// first), a diffusion solve per channel. One channel at a time, its system assembled again and its solver's
// levels taken over from the channel before (built afresh each pass): keeping the three systems tripled the bake's
// memory, and assembling them costs a few per cent of a solve. All the solve's data is freed on return, before the
// grids are written.
SourceValues solveSources(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                                 const MonteCarloVoxels &traced, const Preset &preset, const BakeSettings &settings,
                                 int passes, bool bounceTail, Progress &p, Stopwatch &clock, BakeStats &stats) {
    const bool reference = settings.quality == BakeQuality::Reference;
    const double solved = reference ? kSolvedProgressReference : kSolvedProgress;
    const SubProgress cancel(&p, 0.0, 0.0);  // checked for cancellation by the steps that report no progress
    std::array<UnwrittenVector<double>, 3> phi;  // each solve starts from the previous pass's solution
    for (auto &channel : phi) parallelAssign(channel, topo.size(), 0.0);
    SnowIrradiance fromSnow;  // gathered from other snow onto surface patches (after the first pass)
    SurfaceValues<glm::vec3> before, older;  // the two gathers before it (bounceTail only)
    SourceValues source;
    const SurfaceValues<float> skinRings = skinRingGrowths(scene, topo, cancel);  // the same for every channel and pass
    for (int pass = 0; pass < passes; ++pass) {
        const double begin = 0.4 + (solved - 0.4) * pass / passes, end = 0.4 + (solved - 0.4) * (pass + 1) / passes;
        // A pass after the first gathers first: the first half of its progress, the three solves the rest.
        const double gathered = pass > 0 ? (begin + end) / 2.0 : begin;
        if (pass > 0) {
            // Snow lit by snow: gather the previous pass's radiance and solve again (one bounce a pass).
            p.report(begin, "Gathering light between snow surfaces");
            {
                const GridValues values = gridValues(scene, topo, source, traced, preset, settings, true, cancel);
                if (bounceTail) older = std::move(before), before = std::move(fromSnow.irradiance);
                fromSnow = snowIrradiance(scene, topo, light, source, traced, values, SkyRays(preset.skySamples),
                                          settings.seed ^ 0x5C1Eull, SubProgress(&p, begin, gathered));
                if (preset.skyOverNeighbours)
                    averageOverNeighbours(topo, fromSnow.irradiance), averageOverNeighbours(topo, fromSnow.aim);
                if (bounceTail && pass + 1 == passes && pass > 1) {
                    addBounceTail(topo, pass > 2 ? &older : nullptr, before, fromSnow.irradiance);
                    older = before = SurfaceValues<glm::vec3>();
                }
                source = SourceValues();  // freed (= {} would keep its vectors' capacity)
            }
            releaseFreedMemory();  // the previous pass's values
            clock.lap(&BakeStats::Phases::gather);
        }
        // Each channel's surface terms, held from its solve until the three channels' surfaces are worked out
        // together (their geometry and neighbours read once): the light leaving the surface is not held through
        // the solves.
        std::array<SurfaceTerms, 3> terms;
        {
            // The pass's three solves in the same vectors (held no longer than the pass's solves: the source
            // function and the gathering come after).
            ChannelStorage storage;
            MultigridSolver::Workspace workspace;
            // The last pass splits the light leaving between the beams and the sky where the grids read it: not the
            // reference's surface (path traced).
            const bool splitPass = pass + 1 == passes && !reference && !light.beams.empty() && topo.size() > 0;
            const double feeding = bounceTail ? kExtrapolatedPassTolerance : kGatheredPassTolerance;
            const double tolerance = pass + 1 < passes ? std::max(preset.tolerance, feeding) : preset.tolerance;
            stats.iterations.emplace_back(), stats.relativeResidual.emplace_back();
            for (int c = 0; c < 3; ++c) {
                const SubProgress sub(&p, gathered + (end - gathered) * c / 3.0,
                                      gathered + (end - gathered) * (c + 1) / 3.0);
                p.report(gathered + (end - gathered) * c / 3.0, "Solving multiple scattering");
                // The beams' sources apart (solveBeamsApart) in the next channel's phi, which then starts from
                // this one's.
                const bool beamsApart = splitPass && c == kSplitChannel;
                ChannelSystem system =
                    assemble(scene, topo, light, skinRings, c, sub, std::move(storage),
                             beamsApart ? &phi[c + 1] : nullptr);
                if (pass > 0) system.addDiffuse(fromSnow.irradiance, c);
                system.releaseDiffuseTerms();
                double sources = 0.0;  // W
                if (beamsApart)
                    for (const double v : system.b) sources += v;
                // Albedos differ little between channels.
                if (c > 0 && (pass == 0 || (splitPass && c == kSplitChannel + 1))) parallelCopy(phi[c - 1], phi[c]);
                if (topo.size() > 0) {
                    // The channel before's levels taken over: the rows, blocks and colours are the same.
                    MultigridSolver solver(std::move(system.A), std::move(system.remainder), &workspace);
                    releaseFreedMemory();  // what building the hierarchy freed, before CG's vectors
                    const MultigridSolver::Result result =
                        solver.solve(std::move(system.b), phi[c], tolerance, 500, sub, &workspace);
                    stats.iterations.back()[c] = result.iterations;
                    stats.relativeResidual.back()[c] = result.relativeResidual;
                    if (beamsApart)
                        stats.beamIterations +=
                            solveBeamsApart(topo, solver, workspace, phi[c], sources, phi[c + 1], system.surface, sub);
                    if (c + 1 < 3) {
                        std::tie(storage.A, storage.remainder) = std::move(solver).release(&workspace);
                        storage.b = std::move(workspace.spare);
                    }
                }
                terms[c] = std::move(system.surface);
            }
        }
        p.report(end, "Finding the light leaving the surface");
        SurfaceValues<Source> surface;
        PeakedLobes rampPeaked;
        EdgeFaceLobes edgeFaces;
        SurfaceValues<float> skyShare;
        {
            SurfaceValues<SurfaceLight> leaving(topo.surfaceSlot, topo.surfaceVoxels());
            const SnowLight snow = pass > 0 ? SnowLight{&fromSnow.irradiance, &fromSnow.aim} : SnowLight{};
            // The edge voxels' flat faces' lobes where the grids read them: not where the traced surface stands
            // for them (REFERENCE's last pass).
            const bool flatFaces = !(reference && pass + 1 == passes);
            surfaceLight(scene, topo, light, snow, terms, phi, flatFaces, leaving, edgeFaces, cancel);
            const bool beamsApart = !terms[kSplitChannel].skyLeaving.values().empty();
            terms = {};
            surface = surfaceRadiance(scene.medium->optics(), topo, leaving, cancel);
            skyShare = skyShares(topo, leaving, surface, beamsApart, cancel);
            if (!reference) rampPeaked = rampPeaks(scene, topo, leaving);  // the reference's surface holds no peaks
        }  // the light leaving, freed before the source function
        releaseFreedMemory();  // the surface's arrays (without, the slab's grids peaked 3 bytes per voxel higher)
        if (reference && pass + 1 == passes) {
            p.report(solved, "Path tracing the surface (reference)");
            referenceSurface(scene, topo, preset.referenceSamples, settings.seed, surface,
                             SubProgress(&p, solved, 0.95));
        }
        source = sourceFunction(scene, topo, light, phi, surface, traced, cancel);
        source.rampPeaks = std::move(rampPeaked);
        source.edgeFaces = std::move(edgeFaces);
        source.skyShare = std::move(skyShare);
        clock.lap(&BakeStats::Phases::solve);
    }
    return source;
}

// The distance (m) from x to the nearest snow voxel's centre (density above 0; active tiles by their boxes).
double distanceToSnow(const Medium &medium, const glm::dvec3 &x) {
    const glm::dvec3 p = medium.worldToIndex(x);
    double nearest2 = std::numeric_limits<double>::infinity();  // voxels^2
    openvdb::CoordBBox box;
    for (auto v = medium.density().cbeginValueOn(); v; ++v) {
        if (!(*v > 0.0f) || !v.getBoundingBox(box)) continue;
        const glm::dvec3 d = p - glm::clamp(p, glm::dvec3(box.min().x(), box.min().y(), box.min().z()),
                                            glm::dvec3(box.max().x(), box.max().y(), box.max().z()));
        nearest2 = std::min(nearest2, glm::dot(d, d));
    }
    return std::sqrt(nearest2) * medium.voxelSize();
}

// At most this many beams from area lamps' pieces over all lamps (and no fewer than the lamps): each beam costs a
// march per surface patch and 12 B per snow voxel until the solves end.
constexpr int kMaxLampBeams = 16;

// The scene lit by its area lamps in pieces (lampPieces) as wide as their distance to the snow allows, the widest
// counts lowered first while the pieces exceed kMaxLampBeams.
Scene withLampPieces(const Scene &scene) {
    const Medium &medium = *scene.medium;
    std::vector<glm::ivec2> across;
    int beams = 0;
    for (const Lamp &lamp : scene.lamps) {
        // The bounds are nearer than any snow: a lamp whole by them is whole (the voxel scan only for the others).
        const glm::dvec3 bounded = glm::clamp(lamp.position, medium.boundsMin(), medium.boundsMax());
        glm::ivec2 n = lampPiecesAcross(lamp, glm::length(lamp.position - bounded));
        if (n != glm::ivec2(1)) n = lampPiecesAcross(lamp, distanceToSnow(medium, lamp.position));
        across.push_back(n);
        beams += n.x * n.y;
    }
    const int budget = std::max(kMaxLampBeams, int(scene.lamps.size()));
    while (beams > budget) {
        const auto lamp = std::max_element(across.begin(), across.end(), [](const glm::ivec2 &a, const glm::ivec2 &b) {
            return std::max(a.x, a.y) < std::max(b.x, b.y);
        });
        beams -= lamp->x * lamp->y;
        --(lamp->x >= lamp->y ? lamp->x : lamp->y);
        beams += lamp->x * lamp->y;
    }
    Scene out = scene;
    out.lamps.clear();
    for (std::size_t l = 0; l < scene.lamps.size(); ++l)
        for (const Lamp &piece : lampPieces(scene.lamps[l], across[l])) out.lamps.push_back(piece);
    return out;
}

}  // namespace

BakedGrids emptyBakedGrids(const openvdb::FloatGrid &density, const VolumeOptics &optics,
                           const BakeSettings &settings) {
    if (density.activeVoxelCount() > 0) throw InvalidArgument("the density grid is not empty: bake it");
    BakedGrids out;
    for (int k = 0; k < int(BakedGrids::kCount); ++k)
        out.source[k] = sourceGrid(std::make_shared<openvdb::Vec3fTree>(openvdb::Vec3f(0.0f)), k, 1, density,
                                   optics.extinctionPerDensity, settings);
    return out;
}

BakedGrids bakeScattering(const Scene &scene, const BakeSettings &settings, Progress *progress, BakeStats *stats) {
    validate(scene);
    const Scene lit = withLampPieces(scene);  // the beams' lights; the traced voxels' Monte Carlo samples lamps whole
    const Preset preset = resolve(settings);
    const int sourceScale = sourceScaleFor(*scene.medium, settings);
    Progress quiet;
    Progress &p = progress ? *progress : quiet;
    const bool reference = settings.quality == BakeQuality::Reference;

    BakeStats local;
    Stopwatch clock(local);
    p.report(0.0, "Finding the snow's voxels");
    SnowTopology topo =
        buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(&p, 0.0, 0.05), sourceScale);
    releaseFreedMemory();  // the topology's intermediate lists
    clock.lap(&BakeStats::Phases::topology);
    // Thin snow is traced beside the sun and sky light, which it neither reads nor changes (the same values
    // either way): the car's 3 traced voxels are one task of 0.8 processor seconds, which before held one core
    // while the other idled. The tracing stays on the calling thread and the light is the task beside it: the
    // core's workers run at a lower priority (threads.h), and under load a serial trace on a worker ran slower
    // while the light had the calling thread alone; the light's loop takes both threads once the trace is done.
    // The bar moves by half of what each has done (their reports may land out of order: it never goes back).
    p.report(0.05, kLightAndTraceStage);
    const SideBySideProgress beside(&p, 0.05, 0.4, {0.5, 0.5});
    IncidentLight light;
    std::vector<openvdb::Coord> thin;
    openvdb::BoolTree::Ptr scattered;  // where the renderer scatters (BakedGrids::scatter)
    MonteCarloVoxels traced;
    ThreadSeconds tracing;
    runBeside(
        [&] {
            light = computeIncidentLight(
                lit, topo, {preset.skySamples, preset.sunSamples, settings.seed, preset.skyOverNeighbours},
                beside.step(0));
        },
        [&] {
            tracing = isolatedOnThisThread([&] {
                const SubProgress progress = beside.step(1);
                TracedSnow snow = thinVoxels(*scene.medium, topo);
                // The renderer scatters in the thin snow traced here (docs/vdb-contract.md, firn_scatter).
                scattered = scatterMask(*scene.medium, scatteredVoxels(*scene.medium, snow),
                                        BakedGrids::kScatterOpticalDepth);
                thin = std::move(snow.thin);
                // Light tracing in place of the diffusion where gathering per voxel is over the budget, and its other
                // two uses (transport-thin pieces whole, forward snow at the gathering's cost), with occluders as
                // without (branch trace-quality: over a ground, on a closed box, under a shading plate, better on the
                // mean per block than the diffusion and the gathering; not everywhere: slab_thin over the ground's
                // third view -7 -> -10 %, ball_thin_forward over it seed 2 6.9 -> 7.3 %; docs/bake.md Method 3).
                // Draft traces Preset::lightTracingShare of the photons here and over the budget; at the gathering's
                // cost, what Draft's gathering costs.
                if (settings.lightTracing && !snow.wholePieces.empty()) {  // transport-thin pieces: light traced whole
                    std::vector<openvdb::Coord> whole = thin;
                    whole.insert(whole.end(), snow.wholePieces.begin(), snow.wholePieces.end());
                    traced = lightTraceSources(scene, whole, settings.seed ^ 0x7EACEull, progress, local,
                                               kWholePieceTracedSteps, preset.lightTracingShare);
                    if (!traced.source.empty()) {
                        thin = std::move(whole);
                        if (std::find(snow.inLayer.begin(), snow.inLayer.end(), true) != snow.inLayer.end()) {
                            const bake::FaceGathering faces =
                                layerFaces(scene, preset, thin, std::move(snow.inLayer), settings.seed ^ 0x7EACEull);
                            const bake::FacesTraced taken =
                                addFaceSources(scene, topo, thin, faces, settings.seed ^ 0xFACEull, progress, traced);
                            local.tracedFaces = taken.faces, local.facePaths = taken.paths;
                        }
                    }
                }
                if (traced.source.empty()) {
                    const GatheringPlan plan = planGathering(scene, preset, thin, settings.seed ^ 0x7EACEull);
                    if (settings.lightTracing)
                        traced =
                            lightTracedAtGatheringCost(scene, thin, plan, settings.seed ^ 0x7EACEull, progress, local);
                    if (traced.source.empty()) {
                        local.tracedPaths = plan.paths;
                        if (plan.paths > 0 || thin.empty())
                            traced = traceSources(scene, thin, plan.paths, settings.seed ^ 0x7EACEull, progress,
                                                  plan.drawnPaths);
                        else if (settings.lightTracing)
                            traced = lightTraceSources(scene, thin, settings.seed ^ 0x7EACEull, progress, local,
                                                       kMaxTracedSteps, preset.lightTracingShare);
                        if (plan.paths > 0) {
                            const bake::FacesTraced taken = addFaceSources(scene, topo, thin, gatheredVoxelFaces(plan),
                                                                           settings.seed ^ 0xFACEull, progress, traced);
                            local.tracedFaces = taken.faces, local.facePaths = taken.paths;
                        }
                    }
                }
                progress.report(1.0);  // none traced, or light traced (its fit does not report)
            });
        });
    clock.lap(&BakeStats::Phases::light);
    clock.beside(&BakeStats::Phases::trace, &BakeStats::Phases::light, tracing);
    local.tracedVoxels = traced.source.size();

    local.unknowns = topo.size();
    for (const BoundaryFace &face : topo.faces) ++(face.occluder ? local.occluderFaces : local.airFaces);
    local.surfaceVoxels = topo.surfaceVoxels();
    local.skyTracedVoxels = light.skyTraced;
    const auto &snowRays = light.snowRays.values();
    // Snow hides some patch's sky, or occluders send back enough of the snow's light (bake_snow_irradiance.cpp):
    // gather.
    const bool hidden = light.occluderShare >= kSendBackWorthPasses ||
                        std::any_of(snowRays.begin(), snowRays.end(), [](std::uint64_t r) { return r != 0; });
    // Small pieces and thin snow left to the diffusion (too many to trace: a skier's thousands of lumps) light
    // each other over many bounces: one more gather, and the rest of the bounces from the last two (addBounceTail).
    const bool untracedPieces = !thin.empty() && traced.source.empty();
    const int passes = local.passes = hidden ? 1 + preset.snowBounces + (untracedPieces ? 1 : 0) : 1;
    const SourceValues source =
        solveSources(lit, topo, light, traced, preset, settings, passes, untracedPieces, p, clock, local);
    light = IncidentLight{};  // the grids need it no more
    keepIndexAndPatches(topo);
    p.report(reference ? 0.95 : kSolvedProgress, "Writing the grids");
    BakedGrids grids = makeGrids(lit, topo, source, traced, preset, settings, sourceScale, SubProgress(&p, 1.0, 1.0));
    local.sourceScale = sourceScale;
    local.scatterVoxels = scattered->activeVoxelCount();
    if (local.scatterVoxels > 0) {
        const openvdb::FloatGrid &density = scene.medium->density();
        grids.scatter = scatterGrid(scatteredDensity(*scattered, density.tree(), BakedGrids::kScatterScale), density,
                                    scene.medium->optics().extinctionPerDensity, settings);
        grids.scattered = openvdb::BoolGrid::create(scattered);
        grids.scattered->setTransform(density.transform().copy());
    }
    // Inputs are validated; should a numerical bug still give NaN or inf, fail loudly rather than write it
    // (Cycles would render black or white voxels). Not InvalidArgument: the fuzz driver must see it as a bug.
    // OpenVDB's diagnosis: the leaves in parallel (the car's six grids, 6.9 M values: 0.05-0.06 s on one thread).
    using FiniteCheck = openvdb::tools::CheckFinite<openvdb::Vec3fGrid, openvdb::Vec3fGrid::ValueOnCIter>;
    for (const auto &grid : grids.source)
        if (!openvdb::tools::Diagnose<openvdb::Vec3fGrid>(*grid).check(FiniteCheck()).empty())
            throw std::logic_error("the bake computed a non-finite radiance (NaN or inf); nothing was written");
    clock.lap(&BakeStats::Phases::grids);
    p.report(1.0, "Done");
    if (stats) *stats = local;
    return grids;
}

}  // namespace firn
