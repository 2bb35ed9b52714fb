#include "firn/transport/bake.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <memory>
#include <optional>
#include <queue>
#include <tuple>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/mat4x4.hpp>
#include <glm/mat4x3.hpp>
#include <glm/mat3x3.hpp>
#include <openvdb/tools/Diagnostics.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "firn/transport/bounce_tail.h"
#include "firn/transport/diffusion_links.h"
#include "firn/transport/edge_lobe.h"
#include "firn/transport/half_space.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/light_tracing.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/multigrid.h"
#include "firn/transport/snow_topology.h"
#include "firn/transport/source_lobe.h"
#include "firn/transport/sun_lobe.h"
#include "firn/transport/traced_source.h"
#include "firn/util/error.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"
#include "firn/util/threads.h"
#include "firn/util/version.h"

namespace firn {

namespace {

struct Preset {
    int skySamples, sunSamples;
    double tolerance;
    int referenceSamples;
    int snowBounces;  // passes gathering light between snow surfaces
    int tracedSamples;  // paths per optically thin voxel (thinVoxels)
    int cheapTracedSamples;  // as many where all of them cost little (kCheapTracedSteps, kShortTracedSteps: planGathering)
    // The sky and the light gathered from other snow averaged over like-facing neighbours (averageOverNeighbours):
    // 9 rays a voxel pooled over its neighbours where 16 were its own (docs/bake.md, Performance).
    bool skyOverNeighbours;
};

constexpr int kMaxSunSamples = 4096, kMaxReferenceSamples = 65536;

Preset resolve(const BakeSettings &s) {
    Preset p = s.quality == BakeQuality::Draft ? Preset{8, 1, 1e-4, 0, 1, 64, 64, true}
               : s.quality == BakeQuality::Final ? Preset{9, 4, 1e-5, 0, 1, 256, 1024, true}
                                                 : Preset{64, 8, 1e-7, 64, 2, 1024, 1024, false};
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
    if (s.sourceScale < 0 || s.sourceScale > 4) throw InvalidArgument("bake settings: source scale must be 0 (auto) to 4");
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

// One colour channel of the optics. Lengths below are "resistances": 3 times the reduced optical depth,
// the diffusion distance in units of D (the Marshak boundary sits 2 beyond the last scattering).
struct Channel {
    double k, omega, g;
    double sigmaT(double rho) const { return k * rho; }
    double sigmaTrPerDensity() const { return (1.0 - omega * g) * k; }
    double sigmaTr(double rho) const { return sigmaTrPerDensity() * rho; }  // sigma_a + sigma_s (1 - g)
    double reducedAlbedo() const { return omega * (1.0 - g) / (1.0 - omega * g); }
    double beta() const { return std::sqrt((1.0 - omega) / (3.0 * (1.0 - omega * g))); }  // kappa D
    // What a half-space returns of diffuse light by this diffusion (Marshak's condition, extrapolation 2D):
    // (1 - 2 kappa D) / (1 + 2 kappa D). The voxel scheme returns it so to four digits (its links are exact).
    double diffuseAlbedo() const { return (1.0 - 2.0 * beta()) / (1.0 + 2.0 * beta()); }
};

// Source functions' peaked lobes where they are not zero, by key (an unknown, a place among the grids' values):
// the beams' single scattering lies beneath the shell that takes the surface's radiance (composeSource) and
// above where the snow blocks the beams (639,023 of 2.7 M unknowns on the car sample; held for all, they
// took 24 bytes per unknown while the source is gathered and written).
class PeakedLobes {
  public:
    struct Peak {
        std::uint32_t key;
        glm::vec3 peak0, peak1;
    };
    const std::vector<Peak> &peaks() const { return peaks_; }  // in key order
    static bool holds(const Source &S) { return S.peak0 != glm::vec3(0.0f) || S.peak1 != glm::vec3(0.0f); }
    void add(std::size_t key, const Source &S) {  // keys in increasing order
        if (holds(S)) push({std::uint32_t(key), S.peak0, S.peak1});
    }
    void push(const Peak &peak) {  // keys in increasing order
        const std::size_t word = peak.key / 64;
        if (word >= held_.size()) before_.resize(word + 1, std::uint32_t(peaks_.size())), held_.resize(word + 1, 0);
        held_[word] |= std::uint64_t(1) << (peak.key % 64);
        peaks_.push_back(peak);
    }
    std::vector<Peak>::const_iterator from(std::size_t key) const {  // the first peak of key >= key
        return std::lower_bound(peaks_.begin(), peaks_.end(), key, [](const Peak &p, std::size_t k) { return p.key < k; });
    }
    // The source function of that broad lobe and key: its peak found by counting the keys held before it (a
    // binary search over the car's 640,000 peaks took 0.7 processor seconds of its gathering and grids).
    Source with(const BroadLobe &broad, std::size_t key) const {
        Source S;
        static_cast<BroadLobe &>(S) = broad;
        const std::size_t word = key / 64, bit = key % 64;
        if (word < held_.size() && (held_[word] >> bit & 1)) {
            const Peak &peak = peaks_[before_[word] + __builtin_popcountll(held_[word] & ((std::uint64_t(1) << bit) - 1))];
            S.peak0 = peak.peak0, S.peak1 = peak.peak1;
        }
        return S;
    }

  private:
    std::vector<Peak> peaks_;            // in key order, added by push() alone (the bitmap follows it)
    std::vector<std::uint64_t> held_;    // bit key % 64 of word key / 64: whether key holds a peak
    std::vector<std::uint32_t> before_;  // per word: the peaks of smaller keys
};

// The source function of every unknown.
struct SourceValues {
    std::vector<BroadLobe> broad;  // per unknown
    PeakedLobes peaked;            // by unknown

    Source operator[](std::size_t i) const { return peaked.with(broad[i], i); }
};

// The sources a traced voxel's air neighbours carry where it is open to air on both faces along an axis
// (twoSided) and thick: each face's own, gathered where a camera sees that face (addFaceSources).
struct FaceSources {
    std::array<Source, 6> source;  // by face, -x, +x, -y, +y, -z, +z
    unsigned open = 0;             // bit f: face f holds one
};

// Voxels whose source function comes from Monte Carlo (snow too thin for the diffusion), not from the solve.
struct MonteCarloVoxels {
    openvdb::Int32Tree::Ptr index = std::make_shared<openvdb::Int32Tree>(-1);  // voxel -> source, -1 elsewhere
    openvdb::CoordBBox box;  // around the voxels (empty: none)
    std::vector<Source> source;
    std::vector<std::int32_t> facesAt;  // per source: its place in faces, -1 (or empty) where none
    std::vector<FaceSources> faces;
};

// Voxel -> MonteCarloVoxels' source, -1 elsewhere; one per thread. Outside the traced voxels' box without a tree
// lookup: a lookup where the tree holds no node searches its root every time (the car's 3 traced voxels, looked
// up for each of millions of voxels several times a bake).
class TracedIndex {
  public:
    explicit TracedIndex(const MonteCarloVoxels &traced) : box_(traced.box), index_(*traced.index) {}
    std::int32_t getValue(const openvdb::Coord &c) { return box_.isInside(c) ? index_.getValue(c) : -1; }

  private:
    openvdb::CoordBBox box_;
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index_;
};

// Voxels optically thinner than kTracedOpticalDepth (partly filled voxels of thrown snow, thin flakes, a
// small object's thin fringe) are too thin for a voxel diffusion and take the exact fluence and flux from
// Monte Carlo instead (bench/bake_suite.py: mean errors fell by 1-7 points on balls and lumps, and rose on a
// ball under one transport mean free path at g 0.85; voxels thicker than this were better left to the
// diffusion and its surface radiance, for a voxel's mean fluence is not what a camera sees of its first
// optical depth). Not next to transport-thick snow
// (sigma_tr h >= kThickReducedDepth in the least absorbing channel): that is the fringe of a thick surface,
// whose light the diffusion carries, and paths into such snow would scatter thousands of times.
// Small pieces of snow (at most kSmallPieceVoxels voxels connected through faces, edges or corners: thrown
// lumps, a cloud of them) are traced whole, however thick: a diffusion over a few voxels has no inside, and its
// surfaces' escape function is a half-space's (bench/bake_suite.py: spray_lumps 19.7 -> 11.9 %, spray_dense,
// lumps of up to 20 optical depths per voxel, 34.8 -> 27.0 %; the balls of 5 cm on 1 cm voxels, 500+ voxels,
// stay with the diffusion: ball_forward traced whole was 19.7 % against 17.1 %). Connected through faces only,
// 167 voxels of bits beside the car sample's snow counted as pieces and took 12 s to trace, and the lumps
// of spray_lumps, touching at edges, made pieces of over 125 voxels. Not a small layer of dense snow (a voxel
// too thick or absorbing for a traced layer, no inside or wide in transport mean free paths, every voxel with snow
// or an occluder on one side of each axis): a dusting of 16 x 16 x 1 voxels of sigma_t h 15 on the ground read
// 41.2 % per block, bias -42.3 % traced, 11.1 %, +1.6 % diffused, 10 x 10 x 3 of it 23.4 -> 8.6 %
// (bench/snow_on_ground_bench.py --one-voxel; floating one-voxel layers, diffused, +15 to +59 %).
// Larger pieces that are thin in transport mean free paths (more than kSmallPieceVoxels voxels, but at most
// kMaxTracedPieceReducedVolume summed over them in (sigma_tr h)^3: a ball of transport radius 2.5) have no
// diffusion inside either: ball_forward (5 cm, voxels of optical depth 4, g 0.9, sigma_tr h 0.4: 33 of it, 672
// voxels; the suite's next piece, ball_rgb, 660) read 22.7 % on the rays through its fringe alone and +/-20 %
// inside across the sun with the diffusion. Traced whole they are light traced (light_tracing.h: paths shared by
// the voxels): gathered per voxel, the backward tail of g 0.9 snow's source is too noisy to fit (1024 paths per
// voxel 13.1 %, bias -9.5 %; 8192 paths 8.6 %, -4.6 %, at 29 processor s), light traced 7.2 %, bias -2.3 % at
// 5.4 processor s (docs/bake.md, Accuracy), within a quarter of the budget (kWholePieceTracedSteps) 7.8 %, -2.7 %
// at 1.4 (a tenth: 8.7 %, -4.2 %). Where light tracing is not used (occluders, lamps, over that budget) they are
// diffused as before. Layers have no inside either: a piece none of whose voxels lies kMaxTracedPieceDepth
// transport mean free paths deep (axisDepth: to the air along an axis; a slab up to 5 thick) is traced whole too,
// however wide, where all its voxels are optically thinner than kTracedLayerOpticalDepth and absorb less than
// kTracedLayerAbsorptionDepth each (sigma_a h in the most absorbing channel). Measured on 24 x 24 slabs of 3 voxels
// (bench/bake_suite.py's slab_thin and its views, 4096-path references; docs/benchmarks.md, thin-slab), diffused ->
// traced whole: slab_thin (sigma_t h 2, omega 0.99, g 0.6) 8.0 -> 6.2 %, worst -34 -> +17 %, bias -2.7 -> +0.9 %;
// 4, 5, 6, 8 voxels of it 6.0, 5.2, 6.0, 4.0 -> 5.4, 4.6, 5.1, 4.3 % (half-thicknesses 1.6, 2.0, 2.4, 3.2); omega
// 0.9999 8.9 -> 6.3 %, 0.98 7.7 -> 6.2 %, but 0.95 6.9 -> 6.8 % and 0.9 6.8 -> 8.2 % (bias -8 %: in absorbing snow a
// voxel's mean source is not what a camera sees of its first optical depth); sigma_t h 2.5 mixed (g 0.6: 6.8 -> 8.1
// %, g 0.7: 8.5 -> 7.2 %), 3 and more worse (g 0.6: 6.3 -> 10.4 %; real snow, 10 at g 0.85: 9.0 -> 16.4 %). Along
// the axes, a tilted layer reads up to sqrt(3) deeper and stays with the diffusion sooner.
constexpr double kTracedOpticalDepth = 1.5, kThickReducedDepth = 2.0;
constexpr int kSmallPieceVoxels = 343;  // 7^3
// A small piece larger than this in (sigma_tr h)^3 summed has an inside after all (spray_dense's largest lump 672,
// a 10 x 10 x 3 layer of sigma_t h 15 27,500: traced -20 %; no case between them measured).
constexpr double kMaxTracedSmallPieceReducedVolume = 4096.0;
constexpr double kMaxTracedPieceReducedVolume = 64.0, kMaxTracedPieceDepth = 2.5, kTracedLayerOpticalDepth = 2.25,
                 kTracedLayerAbsorptionDepth = 0.1;
// At most this many paths in all: beyond it, fewer per voxel (a bake must not grow into a hang).
constexpr double kMaxTracedPaths = 2e7;

// What a piece of connected snow is (26-neighbours of non-zero density), as marked in thinVoxels' `done`.
enum PieceKind : std::int32_t { kUnvisited = 0, kSmallPiece = 1, kLargePiece = 2, kTransportThinPiece = 3 };

// How deep `c` lies in its snow: the least reduced optical depth (sigma_tr h = reducedPerDensity * density per
// voxel) from its centre to the air along the six axis directions, `enough` at most. The six walks go in step
// and stop at the least so far: a voxel of a wide thin layer costs its way to the layer's face, not across it.
double axisDepth(Medium::Accessor &density, const openvdb::Coord &c, double reducedPerDensity, double enough) {
    std::array<double, 6> depth;
    depth.fill(0.5 * reducedPerDensity * density.getValue(c));
    double least = enough;
    for (int s = 1;; ++s) {
        bool walking = false;
        for (int a = 0; a < 6; ++a) {
            if (!(depth[a] < least)) continue;
            openvdb::Coord n = c;
            n[a / 2] += a % 2 ? s : -s;
            const float d = density.getValue(n);
            if (d > 0.0f) depth[a] += reducedPerDensity * d, walking = true;
            else least = depth[a];  // the air
        }
        if (!walking) return least;
    }
}

// Whether the unknown at `c` has air (no snow, no occluder) on both faces along some axis.
bool twoSided(const SnowTopology &topo, const openvdb::Coord &c) {
    const std::int32_t i = topo.index->getValue(c);
    if (i < 0) return false;
    for (int a = 0; a < 3; ++a)
        if (topo.isAirFace(std::size_t(i), 2 * a) && topo.isAirFace(std::size_t(i), 2 * a + 1)) return true;
    return false;
}

// The kind of the piece around `seed` (sigma_tr h = reducedPerDensity * density); marks what it visits in `done`.
// Voxels of density `layerBelow` or more make no traced layer. A fill that meets a large piece's voxel stops, and so
// does one past both sizes that is no traced layer: each voxel is visited a bounded number of times, however large
// the snow.
PieceKind pieceAround(Medium::Accessor &density, openvdb::tree::ValueAccessor<openvdb::Int32Tree> &done,
                      const openvdb::Coord &seed, double reducedPerDensity, float layerBelow, const SnowTopology &topo) {
    const auto reducedVolume = [&](const openvdb::Coord &c) { return std::pow(reducedPerDensity * density.getValue(c), 3.0); };
    std::vector<openvdb::Coord> piece{seed}, stack{seed};
    std::size_t shallow = 0;  // piece[0, shallow) lie less than kMaxTracedPieceDepth deep (checked past both sizes)
    const auto hasInside = [&] {
        const double D = kMaxTracedPieceDepth;
        while (shallow < piece.size())
            if (axisDepth(density, piece[shallow++], reducedPerDensity, D) >= D) return true;
        return false;
    };
    done.setValue(seed, kSmallPiece);  // visited by this fill
    double reduced = reducedVolume(seed);
    bool notLayer = !(density.getValue(seed) < layerBelow), large = false;  // a voxel too thick for a traced layer
    while (!stack.empty() && !large) {
        const openvdb::Coord c = stack.back();
        stack.pop_back();
        for (int i = 0; i < 27 && !large; ++i) {
            const openvdb::Coord n = c.offsetBy(i % 3 - 1, i / 3 % 3 - 1, i / 9 - 1);
            if (i == 13 || !(density.getValue(n) > 0.0f)) continue;
            const std::int32_t mark = done.getValue(n);
            if (mark == kLargePiece) large = true;
            else if (mark == kUnvisited) {
                done.setValue(n, kSmallPiece), piece.push_back(n), stack.push_back(n);
                reduced += reducedVolume(n);
                notLayer = notLayer || !(density.getValue(n) < layerBelow);
                large = int(piece.size()) > kSmallPieceVoxels && reduced > kMaxTracedPieceReducedVolume &&
                        (notLayer || hasInside());
            }
        }
    }
    // A small piece with no inside (or wide in transport mean free paths) whose voxels are not all thin enough for
    // a traced layer is a layer of dense snow (a dusting): a camera sees its voxels' first optical depth, not their
    // mean, and the diffusion's surface patches hold it, unless a voxel is open to air on two opposite faces (its
    // density gradient cancels there: no side for its patch to face).
    const auto oneSided = [&] {
        return std::none_of(piece.begin(), piece.end(), [&](const openvdb::Coord &c) { return twoSided(topo, c); });
    };
    const bool small = !large && int(piece.size()) <= kSmallPieceVoxels;
    const bool wide = reduced > kMaxTracedSmallPieceReducedVolume;
    const bool denseLayer = small && notLayer && (wide || !hasInside()) && oneSided();
    const PieceKind kind = large || denseLayer ? kLargePiece : small ? kSmallPiece : kTransportThinPiece;
    if (kind != kSmallPiece)
        for (const openvdb::Coord &c : piece) done.setValue(c, kind);
    return kind;
}

// The voxels traced rather than diffused: `thin`, and the other voxels of transport-thin pieces (`wholePieces`:
// traced too where light tracing takes them, bakeScattering).
struct TracedSnow {
    std::vector<openvdb::Coord> thin, wholePieces;
};

TracedSnow thinVoxels(const Medium &medium, const SnowTopology &topo) {
    const VolumeOptics &optics = medium.optics();
    const double h = medium.voxelSize(), k = optics.extinctionPerDensity;
    const double leastReduced = 1.0 - std::max({optics.albedo.x, optics.albedo.y, optics.albedo.z}) * optics.g;
    const float thinBelow = float(kTracedOpticalDepth / (k * h)), thickFrom = float(kThickReducedDepth / (leastReduced * k * h));
    const double mostAbsorbed = 1.0 - std::min({optics.albedo.x, optics.albedo.y, optics.albedo.z});
    const float layerBelow = float(std::min(kTracedLayerOpticalDepth, kTracedLayerAbsorptionDepth / mostAbsorbed) / (k * h));
    TracedSnow out;
    Medium::Accessor density = medium.accessor();
    openvdb::Int32Tree pieces(kUnvisited);
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> done(pieces);
    for (auto it = medium.density().cbeginValueOn(); it; ++it) {
        if (!(*it > 0.0f)) continue;
        std::int32_t mark = done.getValue(it.getCoord());
        if (mark == kUnvisited) mark = pieceAround(density, done, it.getCoord(), leastReduced * k * h, layerBelow, topo);
        if (mark == kSmallPiece) {
            out.thin.push_back(it.getCoord());
            continue;
        }
        bool nearThick = !(*it < thinBelow);
        for (int dx = -1; dx <= 1 && !nearThick; ++dx)
            for (int dy = -1; dy <= 1 && !nearThick; ++dy)
                for (int dz = -1; dz <= 1 && !nearThick; ++dz)
                    nearThick = density.getValue(it.getCoord().offsetBy(dx, dy, dz)) >= thickFrom;
        if (!nearThick) out.thin.push_back(it.getCoord());
        else if (mark == kTransportThinPiece) out.wholePieces.push_back(it.getCoord());
    }
    return out;
}

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
// ball_half_tau's 2512 at g 0.3 gain too (1.9 -> 1.5 %, the trace 1.04 -> 2.23 s). Long ones keep kCheapTracedSteps: the car's 3 traced voxels in 2.7 M voxels of
// thick snow (thousands of steps per path) took 0.84 -> 2.94 processor s at kShortTracedSteps, for three voxels.
constexpr double kMaxTracedSteps = 2e8, kStepsPerPath = 20.0;  // about 12 processor seconds
constexpr double kCheapTracedSteps = 2e7;                       // about 1.2 processor seconds
constexpr double kWholePieceTracedSteps = kMaxTracedSteps / 4.0;  // transport-thin pieces, light traced whole (thinVoxels)
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
struct GatheringPlan {
    int paths = 0;       // per voxel; 0: none (over the budget)
    double steps = 0.0;  // what they all cost, in tracking steps (the pilot's)
};
GatheringPlan planGathering(const Scene &scene, const Preset &preset, const std::vector<openvdb::Coord> &voxels, std::uint64_t seed) {
    constexpr int kPilotVoxels = 64, kPilotSamples = 4, kMinSamples = 64;
    if (voxels.empty()) return {};
    const MonteCarloReference reference(scene);
    Medium::Accessor density = scene.medium->accessor();
    const double budget = kMaxTracedSteps / (double(voxels.size()) * kMinSamples);  // per path, at the least
    double steps = 0.0, last = 0.0;  // last: voxel v's pilot steps (fewer voxels than pilots repeat theirs)
    int paths = 0;
    for (int k = 0; k < kPilotVoxels; ++k) {
        const std::size_t v = voxels.size() * k / kPilotVoxels;
        if (k == 0 || v != voxels.size() * (k - 1) / kPilotVoxels) {
            // As traceSources gathers it: where cameras see it, those points' draws counted too.
            const bool visible = gatheredWhereSeen(*scene.medium, density, voxels[v]);
            last = double(reference.sourceIn(voxels[v], kPilotSamples, seed, v, true, visible).steps) +
                   kStepsPerPath * kPilotSamples;
        }
        steps += last;
        paths += kPilotSamples;
        if (steps > budget * kPilotVoxels * kPilotSamples) return {};  // too costly already
    }
    const double perPath = steps / paths;
    const int affordable = int(std::min(kMaxTracedPaths, kMaxTracedSteps / perPath) / double(voxels.size()));
    if (affordable < kMinSamples) return {};
    int samples = std::min(affordable, preset.tracedSamples);
    const double cheap = perPath <= kShortPathSteps ? kShortTracedSteps : kCheapTracedSteps;
    while (2 * samples <= preset.cheapTracedSamples && perPath * 2.0 * samples * double(voxels.size()) <= cheap)
        samples *= 2;
    return {samples, perPath * samples * double(voxels.size())};
}

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
        progress.throwIfCancelled();
        Medium::Accessor density = medium.accessor();
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
            out.source[v] = fittedByDirection(medium, density, voxels[v])
                                ? tracedSourceByDirection(estimate(v), directions, visibilityFrom(medium, marcher, voxels[v], directions), g)
                                : tracedSourceByMoments(estimate(v), g);
        }
        progress.report(double(done += range.size()) / voxels.size());
    });
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> index(*out.index);
    for (std::size_t v = 0; v < voxels.size(); ++v) index.setValue(voxels[v], std::int32_t(v)), out.box.expand(voxels[v]);
    return out;
}

// The source function of the given voxels by brute force (MonteCarloReference::sourceIn), `samples` each.
MonteCarloVoxels traceSources(const Scene &scene, const std::vector<openvdb::Coord> &voxels, int samples,
                              std::uint64_t seed, const SubProgress &progress) {
    const MonteCarloReference reference(scene);
    const Medium &medium = *scene.medium;
    return tracedVoxels(reference, voxels, [&](std::size_t v) {
            Medium::Accessor density = medium.accessor();
            return reference.sourceIn(voxels[v], samples, seed, v, true, gatheredWhereSeen(medium, density, voxels[v]));
        }, progress);
}

// A floating layer one voxel thick is seen from each side in that side's first optical depth, which its voxels'
// mean source (the one both its air neighbours carry) is not: at sigma_t h 15, lit from above, the top views read
// -34 % (docs/bake.md, Method 3). Its traced voxels thicker than kMaxDirectionFitTau open to air on both faces
// along an axis gather one source more for each of those faces (MonteCarloReference::sourceIn with the face),
// which the air neighbour there carries (faceCarried): the 16 x 16 x 1 layer at sigma_t h 15 from above 33.3 ->
// 9.1 % per block, bias -34.4 -> -4.1 %, from below 52.4 -> 19.2 %, +47.0 -> +16.3 % (bench/snow_on_ground_bench.py
// --float). A face's paths are a quarter of the voxel's own (64 at least): the layer read 9.7 % against 9.0 % with
// all of them (its points along the normal), the trace 4.2 against 7.3 processor seconds (2.97 without face
// sources). None where the gathering's `plan` and the faces' paths together would cost more than kMaxTracedSteps.
constexpr int kFacePathShare = 4;
void addFaceSources(const Scene &scene, const SnowTopology &topo, const std::vector<openvdb::Coord> &voxels,
                    const GatheringPlan &plan, std::uint64_t seed, MonteCarloVoxels &traced) {
    const int samples = std::max(64, plan.paths / kFacePathShare);
    const Medium &medium = *scene.medium;
    Medium::Accessor density = medium.accessor();
    traced.facesAt.assign(voxels.size(), -1);
    std::vector<std::pair<std::size_t, int>> jobs;  // (voxel, face)
    for (std::size_t v = 0; v < voxels.size(); ++v) {
        const std::int32_t i = topo.index->getValue(voxels[v]);
        if (i < 0 || !(voxelOpticalDepth(medium, density, voxels[v]) > kMaxDirectionFitTau)) continue;
        FaceSources faces;
        for (int a = 0; a < 3; ++a)
            if (topo.isAirFace(std::size_t(i), 2 * a) && topo.isAirFace(std::size_t(i), 2 * a + 1))
                faces.open |= 3u << (2 * a);
        if (!faces.open) continue;
        traced.facesAt[v] = std::int32_t(traced.faces.size());
        traced.faces.push_back(faces);
        for (int f = 0; f < 6; ++f)
            if (faces.open >> f & 1u) jobs.emplace_back(v, f);
    }
    const double faceSteps = plan.steps / (double(plan.paths) * voxels.size()) * samples * jobs.size();
    if (plan.steps + faceSteps > kMaxTracedSteps) {
        traced.facesAt.clear(), traced.faces.clear();
        return;
    }
    const MonteCarloReference reference(scene);
    const double g = medium.optics().g;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, jobs.size(), 4), [&](const auto &range) {
        for (std::size_t j = range.begin(); j != range.end(); ++j) {
            const auto [v, f] = jobs[j];
            const SourceEstimate S = reference.sourceIn(voxels[v], samples, seed, voxels.size() * (1 + f) + v, true, false, f);
            traced.faces[traced.facesAt[v]].source[f] = tracedSourceByMoments(S, g);
        }
    });
}

// The voxels whose gathering costs more than the budget (planGathering: no paths), by light tracing within it
// (light_tracing.h); none where even that costs too much (a cloud of lumps inside thick snow: photons
// scatter thousands of times there), or with lamps (their emission is not sampled) or occluders (planLightTracing).
MonteCarloVoxels lightTraceSources(const Scene &scene, const std::vector<openvdb::Coord> &voxels, std::uint64_t seed,
                                   const SubProgress &progress, BakeStats &stats, double budget = kMaxTracedSteps) {
    const MonteCarloReference reference(scene);
    const LightTracingPlan plan = planLightTracing(reference, voxels, budget, seed);
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

// A solved channel's operator and right-hand side, handed to the next channel's system: of the same sizes, their
// pages are reused rather than mapped and cleared afresh (the kernel's page clearing was 6 % of the car's bake).
struct ChannelStorage {
    Stencil<float> A;
    std::vector<float> remainder;
    std::vector<double> b;
};

// The diffusion system of one channel plus what the surface needs afterwards.
struct ChannelSystem {
    Stencil<float> A;              // what the solver keeps of the operator (MultigridSolver)
    std::vector<float> remainder;  // diag minus the conductances, summed in double
    std::vector<double> b;  // W: diffuse sources at the voxel nodes
    // Surface voxels only (what crosses air faces):
    SurfaceValues<float> escaped;             // W: light leaving through air faces without reaching the node
    SurfaceValues<float> sunEscaped;          // W: of it, the beams' light (scattered above the node)
    SurfaceValues<float> outConductance;      // W per (W/m^2) of fluence: sum of the air faces' conductances
    std::vector<SurfaceValues<float>> sunIn;  // per beam (sun or lamp), W entering through air faces
    SurfaceValues<float> skyIn;               // W entering through air faces
    // Per unit of diffuse irradiance on the surface patch (W/m^2): the node's source and the light
    // returned at once (m^2), so that light from other snow adds to the sources as sky light does.
    SurfaceValues<float> skyToNode, skyReturned;
    SurfaceValues<float> area;  // m^2, surface patch

    ChannelSystem(const SnowTopology &topo, std::size_t beams, ChannelStorage storage)
        : A(std::move(storage.A)), remainder(std::move(storage.remainder)), b(std::move(storage.b)),
          escaped(surfaceZeros(topo)), sunEscaped(surfaceZeros(topo)), outConductance(surfaceZeros(topo)),
          sunIn(beams, surfaceZeros(topo)), skyIn(surfaceZeros(topo)), skyToNode(surfaceZeros(topo)),
          skyReturned(surfaceZeros(topo)), area(surfaceZeros(topo)) {
        b.assign(topo.size(), 0.0);
    }
    static SurfaceValues<float> surfaceZeros(const SnowTopology &topo) {
        return SurfaceValues<float>(topo.surfaceSlot, topo.surfaceVoxels(), 0.0f);
    }

    // Adds diffuse irradiance (W/m^2) on the surface patches.
    void addDiffuse(const SurfaceValues<glm::vec3> &irradiance, int c) {
        for (std::size_t i = 0; i < b.size(); ++i) {
            if (!(area[i] > 0.0f)) continue;  // not a surface voxel
            const double E = irradiance[i][c];
            b[i] += E * skyToNode[i], escaped.surface(i) += E * skyReturned[i], skyIn.surface(i) += E * area[i];
        }
    }
    // Frees what only the assembly and addDiffuse read (12 bytes per surface voxel), before the solver is built.
    void releaseDiffuseTerms() { skyToNode = skyReturned = area = SurfaceValues<float>(); }
};

// Finite volumes with exponential fitting (diffusion_links.h): the links between unknowns, and below those to
// a boundary.

// The stretch from a boundary to the unknown's node, L in resistance, with the boundary condition
// phi = Rb dphi/dR + Phi (Marshak: Rb = 2 for air, 2 (1 + a) / (1 - a) for a Lambertian surface of
// albedo a, Phi = 4 x the diffuse light it sends in / (1 - a)). Exact solution of the stretch.
struct BoundaryLink {
    double beta, Rb, L, sh, ch, delta;  // sh, ch: sinh, cosh of beta L
    BoundaryLink(double beta_, double Rb_, double L_)
        : beta(beta_), Rb(Rb_), L(L_), sh(beta_ * L_ * sinhOverX(beta_ * L_)), ch(std::sqrt(1.0 + sh * sh)),
          delta(Rb_ * beta_ * ch + sh) {}
    double conductance() const { return beta / delta; }  // flux out through the boundary per node fluence
    double mass() const { return beta * (Rb * beta * sh + sh * sh / (ch + 1.0)) / delta; }  // cosh - 1 = sinh^2 / (cosh + 1)
    // A diffuse source at depth R (in resistance) scattering unit power: share reaching the node, and
    // share leaving through the boundary at once.
    double toNode(double R) const { return (Rb * beta * std::cosh(beta * R) + std::sinh(beta * R)) / delta; }
    double toBoundary(double R) const { return std::sinh(beta * (L - R)) / delta; }
    // Diffuse light (irradiance J) arriving through an air boundary: share leaving again at once.
    double diffuseReturned() const { return (sh - 2.0 * beta * ch) / delta; }
};

// Where a beam entering at cosine mu scatters within a stretch L (resistance) above the node: at mean resistance
// 3 mu (reduced depth mu below the surface), cut at the node.
double beamScatteringDepth(double mu, double L) { return 3.0 * mu * (1.0 - std::exp(-L / (3.0 * mu))); }

// What the voxel scheme (assemble) returns of a beam entering a half-space of uniform snow through a flat grid face,
// per W entering: its closed form, exact as its links are (a source at a node R below the boundary, in resistance,
// escapes exp(-beta R) / (1 + 2 beta)). The beam arrives at cosine mu0 and `across` (its cosines to the face's
// other axes) through the top voxel's side faces; voxels are d thick, the top node L below the boundary (both
// resistance). The top voxel scatters what its bottom face does not pass, the share entering through the surface
// at its mean depth (toNode, toBoundary), that through the sides at its node; voxel j below it, at L + j d,
// scatters B0 q^(j - 1/2) (1 - q) of it, a geometric series. On flat slabs of omega 0.98, g 0.85 and omega 0.9,
// g 0.6 overhead it gives 0.387 and 0.266 where the solve returned 0.387 and 0.267 (1D diffusion 0.393, 0.281).
double schemeBeamAlbedo(const Channel &ch, double d, double L, double mu0, double across) {
    const double beta = std::max(ch.beta(), 1e-9);
    const BoundaryLink top(beta, 2.0, L);
    const auto escaping = [&](double R) { return std::exp(-beta * R) / (1.0 + 2.0 * beta); };
    const double B0 = std::exp(-L / (3.0 * mu0)), halfPass = std::exp(-d / (6.0 * mu0));  // beam at the top node; sqrt(q)
    const double R = beamScatteringDepth(mu0, L), side = across * B0;
    const double topReturn = (mu0 * (top.toBoundary(R) + top.toNode(R) * escaping(L)) + side * escaping(L)) / (mu0 + side);
    // (1 - q) / (1 - q exp(-beta d)), q = exp(-d / (3 mu0)), exact where the snow is thin
    const double series = std::expm1(-d / (3.0 * mu0)) / std::expm1(-d / (3.0 * mu0) - beta * d);
    return ch.reducedAlbedo() * ((1.0 - B0 * halfPass) * topReturn + B0 * halfPass * series * escaping(L + d));
}

ChannelSystem assemble(const Scene &scene, const SnowTopology &topo, const IncidentLight &light, int c,
                       const SubProgress &progress, ChannelStorage storage) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    const Channel ch{optics.extinctionPerDensity, optics.albedo[c], optics.g};
    const double h = medium.voxelSize(), h2 = h * h, aPrime = ch.reducedAlbedo();
    const double beta = std::max(ch.beta(), 1e-9);
    const std::size_t n = topo.size();
    ChannelSystem sys(topo, light.beams.size(), std::move(storage));
    // The topology's voxels and links, not copies: the topology outlives the solver (aliasing pointers owning
    // nothing).
    sys.A.coord = std::shared_ptr<const std::vector<openvdb::Coord>>(std::shared_ptr<void>(), &topo.coord);
    sys.A.neighbour = std::shared_ptr<const Stencil<float>::Neighbours>(std::shared_ptr<void>(), &topo.link);
    sys.A.conductance.resize(n), sys.A.diag.resize(n), sys.remainder.resize(n);

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto &range) {
        progress.throwIfCancelled();
        Medium::Accessor density = medium.accessor();
        const SharedLinks links(topo.link, topo.density, ch.sigmaTrPerDensity(), beta, h, range.begin(), range.end());
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const double sigmaTr = ch.sigmaTr(topo.density[i]);
            const SurfacePatch &patch = topo.patches[i];
            double diag = 0.0, source = 0.0;  // W scattered at the node
            std::array<double, 6> mass{};     // absorption each side lends the node
            std::array<std::optional<BoundaryLink>, 6> boundary;
            std::array<double, 6> albedo{};   // occluder faces
            std::array<double, 6> conductance{};  // to the neighbours
            for (int f = 0; f < 6; ++f) {
                const std::int32_t link = topo.link[i][f];
                if (!SnowTopology::isFace(link)) {
                    const Link L = links.at(i, f);
                    conductance[f] = h2 * L.conductance;
                    diag += h2 * L.conductance;
                    mass[f] = h2 * L.halfMass;
                    continue;
                }
                const std::size_t fi = SnowTopology::faceIndex(link);
                const BoundaryFace &face = topo.faces[fi];
                double area = h2;  // m^2 of boundary the face stands for
                if (!face.occluder) {
                    // Air: the density ramps down to zero through any fringe; diffuse sky light (its share
                    // of what falls on the voxel's surface patch) enters through the Marshak condition.
                    // A face on the patch's side counts with its projection on the smooth surface: a
                    // staircase has more face than the surface has area.
                    const double facing = glm::dot(patch.normal, faceNormal(f));
                    if (facing > 0.0 && !patch.sharp) area = h2 * facing;
                    const BoundaryLink &b = boundary[f].emplace(beta, 2.0, 3.0 * ch.sigmaTr(face.rampMass));
                    const double shareOfPatch = patch.area * patch.share[f];  // m^2
                    sys.outConductance.surface(i) += area * b.conductance();
                    sys.skyToNode.surface(i) += 4.0 * shareOfPatch * b.conductance();
                    sys.skyReturned.surface(i) += shareOfPatch * b.diffuseReturned();
                } else {
                    // Occluder: a Lambertian surface at `distance` from the node.
                    albedo[f] = std::min(scene.occluders->albedo(face.triangle)[c], 0.99);
                    const double beyond = ch.sigmaTr(density.getValue(topo.coord[i] + faceStep(f)));
                    const double d = face.distance;
                    boundary[f].emplace(beta, 2.0 * (1.0 + albedo[f]) / (1.0 - albedo[f]),
                                        3.0 * (d * sigmaTr + 0.5 * d * d / h * (beyond - sigmaTr)));
                }
                diag += area * boundary[f]->conductance();
                mass[f] = area * boundary[f]->mass();
            }
            // Absorption: the voxel's own, taken along the axes that meet a boundary (where the fluence
            // varies; exact for a flat surface), or along all three alike inside.
            std::array<double, 3> axisWeight{};
            for (int f = 0; f < 6; ++f) axisWeight[f / 2] += boundary[f] ? 1.0 : 0.0;
            const double weightSum = axisWeight[0] + axisWeight[1] + axisWeight[2];
            for (int a = 0; a < 3; ++a)
                diag += (weightSum > 0.0 ? axisWeight[a] / weightSum : 1.0 / 3.0) * (mass[2 * a] + mass[2 * a + 1]);

            // Sun beams: the power each face lets in or out; the difference is scattered in this voxel.
            std::array<double, 6> groundLight{};  // W/m^2 occluders under the snow send back in
            for (int f = 0; f < 6; ++f)
                if (boundary[f] && albedo[f] > 0.0) groundLight[f] = albedo[f] * light.skyUnderSnow[SnowTopology::faceIndex(topo.link[i][f])][c];
            const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]);
            for (std::size_t s = 0; s < light.beams.size(); ++s) {
                const IncidentLight::Beam &beam = light.beams[s];
                const double Bv = beam.atVoxel[i][c], Bs = beam.atSurface[i][c];  // W/m^2
                if (Bv <= 0.0 && Bs <= 0.0) continue;
                const glm::dvec3 w = towardsBeam(scene, s, centre);
                // Through the surface patch (facing the light: in, else out; at a sharp edge face by face) and
                // through the voxel's other faces. Per air face: W entering, and the cosine it enters at.
                std::array<double, 6> entering{}, muIn{};
                double in = 0.0, out = 0.0;
                for (int f = 0; f < 6 && patch.isSurface(); ++f) {
                    if (patch.share[f] <= 0.0f) continue;
                    const double mu = glm::dot(patch.sharp ? faceNormal(f) : patch.normal, w);
                    const double flow = mu * patch.area * patch.share[f] * (mu > 0.0 ? Bs : Bv);
                    (flow > 0.0 ? in : out) += std::abs(flow);
                    if (flow > 0.0) entering[f] = flow, muIn[f] = mu;
                }
                const double patchIn = in;
                std::array<double, 6> flow{};  // W through each link and occluder face, positive inwards
                for (int f = 0; f < 6; ++f) {
                    const double mu = glm::dot(faceNormal(f), w);
                    const std::int32_t link = topo.link[i][f];
                    if (!SnowTopology::isFace(link)) {
                        flow[f] = h2 * mu * std::sqrt(Bv * double(beam.atVoxel[link][c]));
                    } else if (topo.faces[SnowTopology::faceIndex(link)].occluder && mu < 0.0) {
                        // The beam reaches the surface under the snow.
                        const double B = Bv * std::exp(-sigmaTr * topo.faces[SnowTopology::faceIndex(link)].distance / std::max(-mu, 0.05));
                        flow[f] = h2 * mu * B;
                        groundLight[f] += albedo[f] * -mu * B;
                    }
                    (flow[f] > 0.0 ? in : out) += std::abs(flow[f]);
                }
                if (in <= 0.0) continue;
                const double scattered = aPrime * std::max(0.0, in - out) / in;
                for (int f = 0; f < 6; ++f)
                    if (flow[f] > 0.0) source += scattered * flow[f];
                if (patchIn <= 0.0) continue;
                // Into a surface voxel through its air faces: the beam scatters at its mean depth
                // (beamScatteringDepth); what scatters above the node partly escapes at once.
                sys.sunIn[s].surface(i) += patchIn;
                for (int f = 0; f < 6; ++f) {
                    if (entering[f] <= 0.0) continue;
                    const double P = scattered * entering[f], L = boundary[f]->L;
                    const double R = beamScatteringDepth(muIn[f], L);
                    source += boundary[f]->toNode(R) * P;
                    sys.escaped.surface(i) += boundary[f]->toBoundary(R) * P;
                    sys.sunEscaped.surface(i) += boundary[f]->toBoundary(R) * P;
                }
            }
            // Light reflected by occluders under the snow enters diffusely through their faces.
            for (int f = 0; f < 6; ++f)
                if (groundLight[f] > 0.0)
                    source += 4.0 * groundLight[f] / (1.0 - albedo[f]) * h2 * boundary[f]->conductance();
            const double sky = light.skyOnSurface[i][c];
            for (int f = 0; f < 6; ++f) sys.A.conductance[i][f] = float(conductance[f]);
            sys.A.diag[i] = float(diag);
            sys.remainder[i] = float(rowRemainder(diag, conductance, topo.link[i]));
            sys.b[i] = source + sky * sys.skyToNode[i];
            if (!patch.isSurface()) continue;
            sys.escaped.surface(i) += sky * sys.skyReturned[i];
            sys.area.surface(i) = patch.area;
            sys.skyIn.surface(i) = sky * sys.area[i];
        }
    }, tbb::simple_partitioner());  // runs of at most 1024 unknowns: SharedLinks' buffer stays small
    return sys;
}

// What the solve yields for surface voxels, per channel: the light leaving through their patch, as power
// times angular shape (W; radiance after dividing by pi A).
struct SurfaceLight {
    // What returns of the light that entered there, over and above the escape function's share of it
    // (sharp: it follows shadows; on a sharp edge, SurfacePatch::sharp, the voxel's exit lobe instead, its
    // faces' light fitted already) ...
    BroadLobe returned;
    // ... the beams' light that crosses the snow and leaves through the patch on its far side: a lobe of
    // k = g (l0 in W per channel) about the mean of the beams' directions (per voxel; length <= 1) ...
    glm::vec3 crossing{0.0f}, crossingAxis{0.0f};
    // ... the suns' light returned sharply forwards (smooth patches and sharp edges' faces; SunPeak), the peaked
    // lobe's p0 per channel and grey first moment p1 (radiance, source_lobe.h) ...
    glm::vec3 peak0{0.0f}, peak1{0.0f};
    // ... and all light leaving (W per channel), which leaves in the escape function's shape (smooth,
    // but spread unevenly over a voxel staircase; the suns' light that escaped at once left out: it leaves
    // downstream, SunReturned).
    glm::vec3 leaving{0.0f};
};

// The suns' light the half-space model returns at the smooth patch it entered, which leaves downstream
// (sunLeavingDownstream, by the half-space's displacement `downstream` +- `spread`, m), one channel's: what the
// diffusion misses of it and its share of the sun lobe's shape (W and moments), and what escaped at once (W).
// Held for one channel, from the end of its solve to the end of its surfaceLight (in SurfaceLight, through all
// three solves, it put the car's peak at 311-313 bytes per active voxel; docs/bake.md, Memory).
struct SunReturned {
    float l0 = 0.0f;
    glm::vec3 l1{0.0f};
    float atOnce = 0.0f;
    glm::vec3 downstream{0.0f};
    float spread = 0.0f;
};

// The fluence's gradient along surface voxel i's patch (per m): least squares over the surface voxels of its
// 3^3 block (weighted by the cosine between their normals and its own), in its tangent plane.
glm::dvec3 surfaceGradient(const SnowTopology &topo, const std::vector<double> &phi, std::size_t i, double h) {
    const glm::dvec3 n = topo.patches[i].normal;
    const glm::dvec3 u = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
    const glm::dvec3 v = glm::cross(n, u);
    double a = 0.0, b = 0.0, c = 0.0, ru = 0.0, rv = 0.0;
    for (std::size_t k = topo.neighbourhoodStart[i]; k < topo.neighbourhoodStart[i + 1]; ++k) {
        const std::uint32_t j = topo.neighbourhood[k];
        const double w = std::max(0.0, glm::dot(n, topo.patches[j].normal));
        if (j == i || w <= 0.0) continue;
        const openvdb::Coord d = topo.coord[j] - topo.coord[i];
        const glm::dvec3 step = h * glm::dvec3(d.x(), d.y(), d.z());
        const double x = glm::dot(step, u), y = glm::dot(step, v), f = phi[j] - phi[i];
        a += w * x * x, b += w * x * y, c += w * y * y, ru += w * x * f, rv += w * y * f;
    }
    const double det = a * c - b * b;
    if (det <= 1e-12 * h * h * h * h) return glm::dvec3(0.0);
    return ((c * ru - b * rv) * u + (a * rv - b * ru) * v) / det;
}

// The source function inside unknowns `range` (out[i - range.begin()], zero on entry) from the three channels'
// fluence: S = omega / (4 pi) (phi + 3 g F . w), F = -D grad phi, plus the beams scattered once (the peaked
// lobe). After the solves (during them it would take 48 bytes per unknown).
void insideSource(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                  const std::array<std::vector<double>, 3> &phi, const tbb::blocked_range<std::size_t> &range,
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

// The light leaving voxel i's neighbourhood towards n (leavingOf(j), W) and its area (m^2): the surface voxels
// of its 3^3 block weighted by the cosine between n and their normals, voxels on a sharp edge other than i left
// out (surfaceRadiance says why).
template <typename T, typename LeavingOf>
std::pair<T, double> neighbourhoodOutflow(const SnowTopology &topo, std::size_t i, const glm::dvec3 &n,
                                          const LeavingOf &leavingOf) {
    T leaving(0.0);
    double area = 0.0;
    for (std::size_t k = topo.neighbourhoodStart[i]; k < topo.neighbourhoodStart[i + 1]; ++k) {
        const std::uint32_t j = topo.neighbourhood[k];
        const SurfacePatch &other = topo.patches[j];
        const double w = other.sharp && j != i ? 0.0 : std::max(0.0, glm::dot(n, other.normal));
        leaving += w * leavingOf(j);
        area += w * other.area;
    }
    return {leaving, area};
}

// kg/m^2 of snow from surface voxel i's centre out through its patch: its air faces' ramps by their shares.
double patchRampMass(const SnowTopology &topo, std::size_t i) {
    double mass = 0.0;
    for (int f = 0; f < 6; ++f)
        if (topo.patches[i].share[f] > 0.0f)
            mass += topo.patches[i].share[f] * topo.faces[SnowTopology::faceIndex(topo.link[i][f])].rampMass;
    return mass;
}

// The density of the snow beneath surface voxel i's patch: its neighbour against the normal's largest component
// (its own where that is no snow).
double densityBeneath(const SnowTopology &topo, std::size_t i, const glm::dvec3 &n) {
    const int axis = std::abs(n.x) >= std::max(std::abs(n.y), std::abs(n.z)) ? 0 : std::abs(n.y) >= std::abs(n.z) ? 1 : 2;
    const std::int32_t link = topo.link[i][2 * axis + (n[axis] > 0.0 ? 0 : 1)];
    return SnowTopology::isFace(link) ? topo.density[i] : topo.density[std::size_t(link)];
}

// The beam towards w entering surface voxel i through its faces shared with snow, per W/m^2 at its node and m^2 of
// its patch (schemeBeamAlbedo's `across`: on a flat grid face the cosines to the other axes; a staircase's steps
// let less in so, the voxel's other air faces none).
double acrossSnowFaces(const SnowTopology &topo, std::size_t i, const glm::dvec3 &w, double h) {
    double across = 0.0;
    for (int f = 0; f < 6; ++f)
        if (!SnowTopology::isFace(topo.link[i][f])) across += std::max(0.0, glm::dot(faceNormal(f), w));
    return across * h * h / topo.patches[i].area;
}

// Light returned through a patch (W and the first moments of its linear radiance), over and above the escape
// function's share: of the sky (and light from other snow) and of the beams.
struct ReturnedLight {
    double sky0;
    glm::dvec3 sky1;
    double sun0;
    glm::dvec3 sun1;
    double sunShape0;  // of sun0, sun1: the sun lobe's shape beyond the escape function's
    glm::dvec3 sunShape1;
    double sunMissed, sunReturned;  // W: what the diffusion misses of it; all the half-space returns
};

// The light gathered from other snow onto the surface patches (W/m^2, per channel) and its first moment over the
// directions it arrives from (grey, as IncidentLight::skyAim); none before the first gathering.
struct SnowLight {
    const SurfaceValues<glm::vec3> *light = nullptr, *aim = nullptr;
};

// The sky on a patch of normal n read as an even part and a beam, from the first moment of its arrival
// directions per unit irradiance m (IncidentLight::skyAim): m = (1 - share) 2/3 n + share w, w the beam's unit
// direction towards the light (an even sky's moment is 2/3 n; the share solves |w| = 1). A wall's sky from above
// only is share 0.57 from 48 degrees above its normal: its light, carried on downwards at g 0.7, leaves less
// upwards than an even sky's (docs/bake.md Method 5; bench/wall_on_ground_bench.py).
struct SkyBeam {
    double share = 0.0;
    glm::dvec3 towards{0.0};
};
SkyBeam skyBeamPart(const glm::dvec3 &m, const glm::dvec3 &n) {
    const double delta = glm::dot(m, n) - 2.0 / 3.0, across = glm::length(m - glm::dot(m, n) * n);
    const double share = std::min(1.0, (6.0 * delta + std::sqrt(81.0 * delta * delta + 45.0 * across * across)) / 5.0);
    const glm::dvec3 towards = m - (1.0 - share) * 2.0 / 3.0 * n;  // times share
    if (!(share > 1e-3) || glm::dot(towards, n) <= 0.0) return {};  // none, or light skimming the surface only
    return {share, glm::normalize(towards)};
}

// The unit direction along a surface of normal n in which light travelling along d moves (0 along the normal).
glm::dvec3 travelAlong(const glm::dvec3 &d, const glm::dvec3 &n) {
    const glm::dvec3 t = d - glm::dot(d, n) * n;
    return glm::length(t) > 1e-9 ? glm::normalize(t) : glm::dvec3(0.0);
}

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

// Surface voxel i's downstream kernel (SunReturned::downstream, spread; m): the beams' displacements weighted
// by the power each lets in, on the snow beneath the patch (channel ch's sigma_tr: one kernel for the three).
void downstreamKernel(const Scene &scene, const IncidentLight &light, const ChannelSystem &sys, const Channel &ch,
                      const SnowTopology &topo, std::size_t i, SunReturned &surface) {
    const glm::dvec3 n = topo.patches[i].normal, centre = scene.medium->voxelCentre(topo.coord[i]);
    const double transportPath = 1.0 / ch.sigmaTr(densityBeneath(topo, i, n));  // m
    double power = 0.0, spread = 0.0;
    glm::dvec3 downstream(0.0);
    for (std::size_t s = 0; s < light.beams.size(); ++s) {
        const double P = sys.sunIn[s][i];
        if (P <= 0.0) continue;
        const glm::dvec3 d = -towardsBeam(scene, s, centre);
        const Displacement k = halfSpaceDisplacement(std::clamp(-glm::dot(d, n), 0.05, 1.0));
        downstream += P * k.mean * travelAlong(d, n);
        spread += P * k.spread, power += P;
    }
    if (power <= 0.0) return;
    surface.downstream = glm::vec3(transportPath / power * downstream);
    surface.spread = float(transportPath * spread / power);
}

// The rotation taking unit vector `from` to unit vector `to` (the shorter way; from . to > -1), applied to v.
glm::dvec3 rotatedWith(const glm::dvec3 &v, const glm::dvec3 &from, const glm::dvec3 &to) {
    const glm::dvec3 axis = glm::cross(from, to);  // sin times the unit axis
    const double cos = glm::dot(from, to);
    return cos * v + glm::cross(axis, v) + axis * (glm::dot(axis, v) / (1.0 + cos));
}

// The weight surface voxel i's downstream kernel gives surface voxel j of its 3^3 block (before normalizing): a
// Gaussian of the half-space's displacement (SunReturned::downstream, spread) in i's tangent plane, times j's patch
// area and the cosine between the normals; smooth patches only.
double downstreamWeight(const SnowTopology &topo, const SunReturned &from, std::size_t i, std::size_t j, double h) {
    const SurfacePatch &a = topo.patches[i], &b = topo.patches[j];
    const double facing = glm::dot(a.normal, b.normal);
    if (b.sharp || facing <= 0.0) return 0.0;
    if (from.spread <= 0.0f) return i == j ? 1.0 : 0.0;
    const openvdb::Coord d = topo.coord[j] - topo.coord[i];
    glm::dvec3 step = h * glm::dvec3(d.x(), d.y(), d.z());
    step -= glm::dot(step, a.normal) * a.normal;
    const glm::dvec3 off = step - glm::dvec3(from.downstream);
    return facing * b.area * std::exp(-glm::dot(off, off) / (2.0 * double(from.spread) * double(from.spread)));
}

// Channel c's sun light each smooth patch returns at once (`sun`; its atOnce averaged over the neighbourhood as the
// outflow is, for a staircase lets it out unevenly), where it leaves: over the surface voxels of its 3^3 block by
// downstreamWeight, the weights of each sender summing to one (the power is kept), the forms turned with the normal,
// added to the receivers' returned light; what escaped at once is taken out of their `leaving`. A flat, evenly lit
// surface receives what it sends (the flat slabs unchanged); past a terminator the patches downstream take what
// entered before it (docs/bake.md, Method 5).
void sunLeavingDownstream(const SnowTopology &topo, const SurfaceValues<SunReturned> &sun, int c, double h,
                          SurfaceValues<SurfaceLight> &out) {
    SurfaceValues<float> total(topo.surfaceSlot, topo.surfaceVoxels(), 0.0f);   // each sender's weights' sum
    SurfaceValues<float> atOnce(topo.surfaceSlot, topo.surfaceVoxels(), 0.0f);  // W sent, averaged
    auto smooth = [&](std::size_t i) { return topo.patches[i].isSurface() && !topo.patches[i].sharp; };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!smooth(i)) continue;
            const auto [leaving, area] = neighbourhoodOutflow<double>(
                topo, i, topo.patches[i].normal, [&](std::size_t j) { return double(sun[j].atOnce); });
            atOnce.surface(i) = float(leaving / area * double(topo.patches[i].area));
            double sum = 0.0;
            for (std::size_t k = topo.neighbourhoodStart[i]; k < topo.neighbourhoodStart[i + 1]; ++k)
                sum += downstreamWeight(topo, sun[i], i, topo.neighbourhood[k], h);
            total.surface(i) = float(sum);
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        for (std::size_t j = range.begin(); j != range.end(); ++j) {
            if (!smooth(j)) continue;
            const glm::dvec3 to = topo.patches[j].normal;
            float l0 = 0.0f;
            glm::vec3 l1(0.0f);
            for (std::size_t k = topo.neighbourhoodStart[j]; k < topo.neighbourhoodStart[j + 1]; ++k) {
                const std::uint32_t i = topo.neighbourhood[k];
                if (!smooth(i) || !(total[i] > 0.0f)) continue;
                const double w = downstreamWeight(topo, sun[i], i, j, h) / total[i];
                if (w <= 0.0) continue;
                // what escaped at once in the escape function's shape
                l0 += float(w * (sun[i].l0 + 3.0 / 7.0 * atOnce[i]));
                l1 += glm::vec3(w * (rotatedWith(glm::dvec3(sun[i].l1), topo.patches[i].normal, to) +
                                     6.0 / 7.0 * atOnce[i] * to));
            }
            SurfaceLight &received = out.surface(j);
            received.returned.l0[c] += l0;
            received.returned.l1[c] += l1;
            received.leaving[c] -= sun[j].atOnce;
        }
    });
}

// Channel c's light leaving each surface voxel, from its solve.
void surfaceLight(const Scene &scene, const SnowTopology &topo, const IncidentLight &light, const SnowLight &snow,
                  const ChannelSystem &sys, const std::vector<double> &phi, int c, SurfaceValues<SurfaceLight> &out) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    const Channel ch{optics.extinctionPerDensity, optics.albedo[c], optics.g};
    const Channel kernelChannel{optics.extinctionPerDensity, optics.albedo[1], optics.g};  // one kernel for the three
    SurfaceValues<SunReturned> sun(topo.surfaceSlot, topo.surfaceVoxels());
    const double y = absorptionParameter(ch.omega, ch.g);
    // Where the snow absorbs, the diffusion returns other amounts than a half-space of this snow does (the sun
    // lobe's Monte Carlo table): of diffuse light less (the spherical albedo 0.447 against Marshak's 0.429 at
    // omega 0.98, g 0.85; 0.330 against 0.300 at omega 0.9, g 0.6), of a beam more at steep incidence and less at
    // grazing (the voxel scheme's 0.387 against 0.353 at mu0 1, 0.505 against 0.571 at mu0 0.3, omega 0.98,
    // g 0.85: schemeBeamAlbedo, on the snow beneath the patch). What it misses (negative where it returns too
    // much) leaves too: an absorbing ball's shadowed side, lit by the sky alone, was 5-9 % too dark, its sunward
    // face 5-8 % too bright (docs/bake.md, Accuracy).
    const double diffuseMissed = sphericalAlbedo(ch.g, y) - ch.diffuseAlbedo();
    const double h = medium.voxelSize();
    // Sun light that entered returns as a half-space of this snow returns it, with the sun lobe's albedo and
    // shape; sky light isotropically (a non-absorbing half-space returns uniform sky light so; absorption takes
    // the escape function's shape from it, by reciprocity with ART's plane albedo). What the diffusion says
    // beyond that (absorbed sky light, light gone elsewhere, light from deep inside, from the ground or from
    // neighbouring snow) and what it misses take the escape function's u(mu) = 3/7 + 6/7 mu. So:
    // leaving = sum returned (shape - u) + (out + missed) u. The returned part (W, moments of a linear form)
    // through a surface of normal n taking `skyShare` of voxel i's sky light and beamShare(s) of each beam's; with
    // `peak` (a smooth patch, or each air face of a sharp edge), the suns' light returned sharply forwards leaves as
    // the peaked lobe instead (SunPeak: at grazing sun the lit rim seen against the sun, bench/bake_halfspace.py),
    // added to `peak` (radiance), the rest linear:
    auto returnedThrough = [&](std::size_t i, const glm::dvec3 &n, double skyShare, const auto &beamShare,
                               SurfaceLight *peak) {
        const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]), escape1 = 6.0 / 7.0 * n;
        const double sky = skyShare * sys.skyIn[i];
        double r0 = sky * (1.0 - 3.0 / 7.0), missed = sky * diffuseMissed;  // W
        glm::dvec3 r1 = -sky * escape1;
        // A smooth patch's lopsided diffuse light (sky, occluders' reflections and other snow's light, each from
        // where it arrives) returns as its beam part would, in the sun lobe's shape (a + b n.w + c t.w against the
        // even 1: the same exitance, a + 2b/3 = 1). Not a sharp edge's faces: the moment is over the patch
        // normal's hemisphere, and an even sky would lean 45 degrees off each face.
        const glm::dvec3 snowE = snow.light ? glm::dvec3((*snow.light)[i]) : glm::dvec3(0.0);
        const glm::dvec3 E = glm::dvec3(light.skyOnSurface[i]) + snowE;
        const double grey = (E.x + E.y + E.z) / 3.0;
        if (!topo.patches[i].sharp && grey > 0.0) {
            const glm::dvec3 snowAim = snow.aim ? glm::dvec3((*snow.aim)[i]) : glm::dvec3(0.0);
            const SkyBeam beam = skyBeamPart((glm::dvec3(light.skyAim[i]) + snowAim) / grey, n);
            if (beam.share > 0.0) {
                const SunLobe lobe = sunLobe(ch.g, std::clamp(glm::dot(beam.towards, n), 0.05, 1.0), y);
                const double returned = beam.share * lobe.albedo * sky;
                r0 += returned * (lobe.a - 1.0);
                r1 += returned * (lobe.b * n + lobe.c * travelAlong(-beam.towards, n));
            }
        }
        double sun0 = 0.0, sunMissed = 0.0, sunReturned = 0.0;  // the beams' part
        glm::dvec3 sun1(0.0);
        // The half-space of the snow beneath the patch: a voxel's resistance and the node's below the surface
        // (schemeBeamAlbedo's d, L). A smooth surface's fringe voxel holds less snow where the surface crosses it
        // (antialiasing), its ramp: the snow's own density for d, not the fringe's (with the fringe's ball_grey
        // was 12.6 % where it is 11.5 %, docs/bake.md).
        const double voxelR = 3.0 * h * ch.sigmaTr(densityBeneath(topo, i, n)), nodeR = 3.0 * ch.sigmaTr(patchRampMass(topo, i));
        for (std::size_t s = 0; s < light.beams.size(); ++s) {
            const double P = sys.sunIn[s][i] * beamShare(s);
            if (P <= 0.0) continue;
            const glm::dvec3 d = -towardsBeam(scene, s, centre);  // where the light travels
            const double mu0 = std::clamp(-glm::dot(d, n), 0.05, 1.0);
            const SunLobe lobe = sunLobe(ch.g, mu0, y);
            const glm::dvec3 t = travelAlong(d, n);
            const double returned = P * lobe.albedo;
            sunReturned += returned;
            sunMissed += P * (lobe.albedo - schemeBeamAlbedo(ch, voxelR, nodeR, mu0, acrossSnowFaces(topo, i, -d, h)));
            if (!peak) {
                sun0 += returned * (lobe.a - 3.0 / 7.0);
                sun1 += returned * (lobe.b * n + lobe.c * t - escape1);
                continue;
            }
            const SunPeak split = sunPeak(ch.g, mu0, y, lobe);
            sun0 += returned * ((1.0 - split.share) * split.a() - 3.0 / 7.0);
            sun1 += returned * ((1.0 - split.share) * (split.b * n + split.c * t) - escape1);
            const double p0 = split.mean * returned / (kPi * topo.patches[i].area);
            const glm::dvec3 m = std::cos(split.elevation) * t + std::sin(split.elevation) * n;
            peak->peak0[c] += float(p0);
            peak->peak1 += glm::vec3(split.k * p0 * glm::normalize(m));  // 3 k m mean(p0), channel c's part
        }
        return ReturnedLight{r0 + missed * 3.0 / 7.0, r1 + missed * escape1, sun0 + sunMissed * 3.0 / 7.0,
                             sun1 + sunMissed * escape1, sun0, sun1, sunMissed, sunReturned};
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!topo.patches[i].isSurface()) continue;
            const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]);
            const SurfacePatch &patch = topo.patches[i];
            const double leaving = sys.escaped[i] + sys.outConductance[i] * phi[i];
            SurfaceLight &surface = out.surface(i);
            const ReturnedLight r = returnedThrough(i, patch.normal, 1.0, [](std::size_t) { return 1.0; },
                                                    patch.sharp ? nullptr : &surface);
            // The similarity-reduced beam is forward-scattered light: where it reaches a patch from inside
            // it leaves around its direction, as a lobe of k = g (its exitance taken as pi l0 (1 + 3 k cos)),
            // through the smooth surface or, at a sharp edge, through each air face.
            const double k = crossingAnisotropy(ch.g);
            double crossing = 0.0;
            glm::dvec3 axis(0.0);
            for (std::size_t s = 0; s < light.beams.size(); ++s) {
                const double beam = light.beams[s].atVoxel[i][c];
                const glm::dvec3 d = -towardsBeam(scene, s, centre);
                for (int f = 0; f < 6 && beam > 0.0; ++f) {
                    const double cos = glm::dot(d, patch.sharp ? faceNormal(f) : patch.normal);
                    if (patch.share[f] <= 0.0f || cos <= 0.0) continue;
                    const double l0 = beam * cos * patch.area * patch.share[f] / (kPi * (1.0 + 3.0 * k * cos));
                    crossing += l0, axis += l0 * d;
                }
            }
            // Light flowing along the surface leaves leaning the way it flows: the diffusion's radiance
            // (phi + 3 F . w) / 4 pi holds the tangential flux F_t = -D grad_t phi, which the escape function (the
            // flux across the surface) does not; added to the exit form relative to phi, 3 F_t / phi, it moves no
            // exitance (t . w integrates to zero over the hemisphere). Past a ball's terminator the fluence falls
            // away from the lit side, and on its sunward face away from the point under the sun (docs/bake.md,
            // Accuracy: the terminator). At most 3/7, so the form stays positive at grazing exit.
            glm::dvec3 drift(0.0);
            if (!patch.sharp && phi[i] > 0.0) {
                const glm::dvec3 g = surfaceGradient(topo, phi, i, h);
                const double sigmaTr = ch.sigmaTr(densityBeneath(topo, i, patch.normal));
                drift = -(g - glm::dot(g, patch.normal) * patch.normal) / (sigmaTr * phi[i]);
                const double length = glm::length(drift);
                if (length > 3.0 / 7.0) drift *= 3.0 / 7.0 / length;
            }
            surface.crossing[c] = float(crossing);
            if (crossing > 0.0) surface.crossingAxis = glm::vec3(axis / crossing);
            if (patch.sharp) {
                surface.returned.l0[c] = float(r.sky0 + r.sun0);
                surface.returned.l1[c] = glm::vec3(r.sky1 + r.sun1 + leaving * drift);
                surface.leaving[c] = float(leaving);
                continue;
            }
            // The suns' light the half-space returns at the patch it entered leaves downstream (sunLeavingDownstream):
            // what escaped at once and what the diffusion misses, with their share of the sun lobe's shape (the
            // rest of the shape goes with the light the diffusion carries from the node). The peaked lobe stays:
            // single scattering at grazing sun leaves within a mean free path, a small part of 1/sigma_tr.
            const double atOnce = sys.sunEscaped[i];
            const double moved = r.sunReturned > 0.0 ? std::clamp((atOnce + r.sunMissed) / r.sunReturned, 0.0, 1.0) : 0.0;
            surface.returned.l0[c] = float(r.sky0 + (1.0 - moved) * r.sunShape0);
            surface.returned.l1[c] = glm::vec3(r.sky1 + (1.0 - moved) * r.sunShape1 + leaving * drift);
            surface.leaving[c] = float(leaving);
            SunReturned &sunHere = sun.surface(i);
            sunHere.l0 = float(moved * r.sunShape0 + r.sunMissed * 3.0 / 7.0);
            sunHere.l1 = glm::vec3(moved * r.sunShape1 + r.sunMissed * 6.0 / 7.0 * patch.normal);
            sunHere.atOnce = float(atOnce);
            // The same kernel for each channel, found again per channel (a loop over the beams): held through the
            // three solves it would add 16 bytes per surface voxel at the solves' peak (docs/bake.md, Memory).
            downstreamKernel(scene, light, sys, kernelChannel, topo, i, sunHere);
        }
    });
    // Sharp edges: each air face's own exit radiance (the light returned through it, the exitance of the
    // surface voxels facing its way, other edge voxels left out as in surfaceRadiance), and the one lobe
    // fitted to what cameras see of them (edgeLobe). A face the sun enters at grazing incidence returns it
    // sharply forwards as a smooth surface does: its SunPeak joins the voxel's peaked lobe (a small lump's edges
    // are its rim against the sun, docs/bake.md Method 5: lump_angles_bench's view 27 degrees off the sun's travel
    // -39.5 -> -16.0 %).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        std::vector<FaceExit> faces;
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const SurfacePatch &patch = topo.patches[i];
            if (!patch.sharp) continue;
            const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]);
            faces.clear();
            for (int f = 0; f < 6; ++f) {
                if (patch.share[f] <= 0.0f) continue;
                const glm::dvec3 n = faceNormal(f);
                const ReturnedLight r = returnedThrough(i, n, patch.share[f], [&](std::size_t s) {
                    const glm::dvec3 w = towardsBeam(scene, s, centre);  // the beam entered each face by its cosine
                    double total = 0.0;
                    for (int g = 0; g < 6; ++g)
                        if (patch.share[g] > 0.0f) total += std::max(0.0, glm::dot(faceNormal(g), w));
                    return total > 0.0 ? std::max(0.0, glm::dot(n, w)) / total : 0.0;
                }, &out.surface(i));
                const auto [leaving, area] =
                    neighbourhoodOutflow<double>(topo, i, n, [&](std::size_t j) { return double(out[j].leaving[c]); });
                const double exitance = area > 0.0 ? leaving / area : 0.0, own = kPi * h * h;
                faces.push_back({n, (r.sky0 + r.sun0) / own + exitance * (3.0 / 7.0 / kPi),
                                 (r.sky1 + r.sun1) / own + exitance * 6.0 / 7.0 / kPi * n});
            }
            const SourceLobe lobe = edgeLobe(faces);
            out.surface(i).returned.l0[c] = float(lobe.l0);
            out.surface(i).returned.l1[c] = glm::vec3(lobe.l1);
        }
    });
    sunLeavingDownstream(topo, sun, c, h, out);
}

// Radiance leaving each surface voxel. The returned part is the voxel's own (over its patch's area); the
// light leaving in the escape function's shape is averaged over the voxel's neighbourhood (surface voxels
// of its 3^3 block facing the same way, weighted by the cosine between the normals, by area): a voxel
// staircase spreads the diffusion's outflow unevenly between steps, though the light itself varies only
// over a few transport mean free paths. The shape follows the voxel's own normal. Voxels on a sharp edge
// are left out of their neighbours' averages: their outflow leaves through two or three faces at once (the
// lit top's light spread down a shadowed side a voxel or two, bench/bake_suite.py box_sharp: 8.7 % mean
// error with them, 5.4 % without).
SurfaceValues<Source> surfaceRadiance(const VolumeOptics &optics, const SnowTopology &topo,
                                      const SurfaceValues<SurfaceLight> &solved) {
    SurfaceValues<Source> out(topo.surfaceSlot, topo.surfaceVoxels());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!topo.patches[i].isSurface()) continue;
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
                // The crossing beams, added by their moments: light scattered forwards many times is broader
                // than one scattering's peak (in the peaked lobe, k = g: ball_forward 17.6 % against 17.1 %, seen
                // against the sun -29 % against -21 %; spray_lumps 20.1 % against 19.7 %; docs/bake.md).
                const double crossing = solved[i].crossing[c] / topo.patches[i].area;  // its lobe's l0 (radiance)
                out.surface(i).l0[c] = float(lobe.l0 + crossing);
                out.surface(i).l1[c] =
                    glm::vec3(lobe.l1 + 3.0 * crossingAnisotropy(optics.g) * crossing * glm::dvec3(solved[i].crossingAxis));
            }
            out.surface(i).peak0 = solved[i].peak0, out.surface(i).peak1 = solved[i].peak1;
        }
    });
    return out;
}

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

// The source function of every unknown: inside (insideSource) composed with the surface's (composeSource), a
// block of unknowns at a time. Traced voxels hold their Monte Carlo source instead of the diffusion's, also
// where a surface's values are carried beyond the snow: a thin object's surface voxels are traced, and its rim
// shows their light.
SourceValues sourceFunction(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                            const std::array<std::vector<double>, 3> &phi, const SurfaceValues<Source> &surface,
                            const MonteCarloVoxels &traced) {
    constexpr std::size_t kBlock = 1024;
    SourceValues out;
    out.broad.resize(topo.size());
    std::vector<std::vector<PeakedLobes::Peak>> peaked((topo.size() + kBlock - 1) / kBlock);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, peaked.size(), 1), [&](const auto &blocks) {
        TracedIndex tracedIndex(traced);
        std::vector<Source> values;
        for (std::size_t b = blocks.begin(); b != blocks.end(); ++b) {
            const tbb::blocked_range<std::size_t> range(b * kBlock, std::min(topo.size(), (b + 1) * kBlock));
            values.assign(range.size(), Source{});
            insideSource(scene, topo, light, phi, range, values.data());
            composeSource(topo, surface, range, values.data());
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                Source &S = values[i - range.begin()];
                if (const std::int32_t t = tracedIndex.getValue(topo.coord[i]); t >= 0) S = traced.source[t];
                out.broad[i] = S;
                if (PeakedLobes::holds(S)) peaked[b].push_back({std::uint32_t(i), S.peak0, S.peak1});
            }
        }
    });
    for (const auto &block : peaked)
        for (const PeakedLobes::Peak &peak : block) out.peaked.push(peak);
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
                    const auto form = fitAround(faceNormal(f), topo.size() + i * 6 + std::uint64_t(f));  // streams of its own
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
                    const SourceLobe lobe = exitLobe(form[c][0], glm::dvec3(form[c][1], form[c][2], form[c][3]), patch.normal);
                    out.surface(i).l0[c] = float(lobe.l0);
                    out.surface(i).l1[c] = glm::vec3(lobe.l1);
                }
            }
            out.surface(i).peak0 = out.surface(i).peak1 = glm::vec3(0.0f);  // the traced radiance is all of it
            progress.report(double(++done) / surface.size());
        }
    });
}

// The radiance the surface voxels around voxel c (outside the snow) show towards it: their values
// weighted by how much their surface faces c (a voxel beside an edge takes the side's, one above it the
// top's). False if no surface voxel is near.
bool facingAverage(const SnowTopology &topo, const openvdb::Coord &c,
                   openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, const SourceValues &source,
                   Source &S) {
    double total = 0.0;
    int count = 0;
    glm::dvec3 l0(0.0), peak0(0.0), peak1(0.0);
    glm::dmat3 l1(0.0);
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
                const std::int32_t j = index.getValue(c.offsetBy(-dx, -dy, -dz));
                if (j < 0 || !topo.patches[j].isSurface()) continue;
                const double w = std::max(0.0, glm::dot(topo.patches[j].normal, glm::normalize(glm::dvec3(dx, dy, dz))));
                const Source v = source[j];
                l0 += w * glm::dvec3(v.l0), l1 += w * glm::dmat3(v.l1);
                peak0 += w * glm::dvec3(v.peak0), peak1 += w * glm::dvec3(v.peak1);
                total += w, ++count;
            }
    if (count == 0) return false;
    if (total <= 0.0) {  // nothing faces c: plain average
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const std::int32_t j = index.getValue(c.offsetBy(dx, dy, dz));
                    if (j < 0 || !topo.patches[j].isSurface()) continue;
                    const Source v = source[j];
                    l0 += glm::dvec3(v.l0), l1 += glm::dmat3(v.l1), total += 1.0;
                    peak0 += glm::dvec3(v.peak0), peak1 += glm::dvec3(v.peak1);
                }
    }
    S.l0 = glm::vec3(l0 / total);
    S.l1 = glm::mat3(l1 / total);
    S.peak0 = glm::vec3(peak0 / total), S.peak1 = glm::vec3(peak1 / total);
    return true;
}

// What air voxel c carries of its face neighbours' face sources (MonteCarloVoxels::faces) towards it, averaged;
// false where none holds one.
bool faceCarried(const openvdb::Coord &c, TracedIndex &tracedIndex, const MonteCarloVoxels &traced, Source &S) {
    if (traced.faces.empty()) return false;
    Source sum;
    int count = 0;
    for (int f = 0; f < 6; ++f) {
        openvdb::Coord n = c;
        n[f / 2] -= f % 2 ? 1 : -1;  // the neighbour whose face f is c's
        const std::int32_t t = tracedIndex.getValue(n);
        if (t < 0 || traced.facesAt[t] < 0 || !(traced.faces[traced.facesAt[t]].open >> f & 1u)) continue;
        const Source &v = traced.faces[traced.facesAt[t]].source[f];
        sum.l0 += v.l0, sum.l1 += v.l1, sum.peak0 += v.peak0, sum.peak1 += v.peak1, ++count;
    }
    if (!count) return false;
    S.l0 = sum.l0 / float(count), S.l1 = sum.l1 / float(count);
    S.peak0 = sum.peak0 / float(count), S.peak1 = sum.peak1 / float(count);
    return true;
}

using VoxelValue = std::pair<openvdb::Index, BroadLobe>;  // offset in its leaf, value

// Source functions at voxels, in order: broad lobes, with the peaked lobes by place (PeakedLobes).
struct VoxelValues {
    std::vector<VoxelValue> values;
    PeakedLobes peaked;

    void add(openvdb::Index offset, const Source &S) {
        peaked.add(values.size(), S);
        values.emplace_back(offset, S);
    }
    void append(const VoxelValues &other, std::size_t begin, std::size_t end) {  // other's values [begin, end)
        for (auto peak = other.peaked.from(begin); peak != other.peaked.peaks().end() && peak->key < end; ++peak)
            peaked.push({std::uint32_t(values.size() + peak->key - begin), peak->peak0, peak->peak1});
        values.insert(values.end(), other.values.begin() + begin, other.values.begin() + end);
    }
    Source operator[](std::size_t k) const { return peaked.with(values[k].second, k); }
};

// Values by leaf of the grids' topology: leaf l's lie at [start[l], start[l + 1]) and, where a second block was
// appended after the first, at [later[l], later[l + 1]).
struct LeafValues : VoxelValues {
    std::vector<std::size_t> start, later;

    // One block: perLeaf's values leaf by leaf (consumed), with room for `more` values after them, so that a
    // second block appended within it does not move the first (the old array and the new together were the car's
    // gathering peak). Room never written holds no memory (the pages of a large array are the system's until used).
    LeafValues(std::vector<VoxelValues> &&perLeaf, std::size_t more) : start{0} {
        std::size_t total = 0;
        for (const auto &leaf : perLeaf) total += leaf.values.size();
        values.reserve(total + more);
        for (VoxelValues &leaf : perLeaf) {
            append(leaf, 0, leaf.values.size());
            leaf = VoxelValues();  // (= {} would keep its capacity)
            start.push_back(values.size());
        }
        later.assign(start.size(), values.size());
    }
    // first's block taken over as it is (a copy of it was the gathering's and the grids' memory peak), then
    // `then`'s values leaf by leaf (consumed).
    LeafValues(LeafValues &&first, std::vector<VoxelValues> &&then)
        : VoxelValues(std::move(first)), start(std::move(first.start)), later{values.size()} {
        std::size_t total = values.size();
        for (const auto &leaf : then) total += leaf.values.size();
        values.reserve(total);
        for (VoxelValues &leaf : then) {
            append(leaf, 0, leaf.values.size());
            leaf = VoxelValues();
            later.push_back(values.size());
        }
    }
    template <typename Body>
    void forEachIn(std::size_t l, const Body &body) const {  // body(k) for leaf l's values
        for (std::size_t k = start[l]; k < start[l + 1]; ++k) body(k);
        for (std::size_t k = later[l]; k < later[l + 1]; ++k) body(k);
    }
    bool emptyIn(std::size_t l) const { return start[l] == start[l + 1] && later[l] == later[l + 1]; }
};

// at: the voxels with values -> their place in `values` (by leaf of `leaves`), with leaves only where values are
// (over all the grids' leaves it took 17 bytes per unknown on the car).
void placeValues(const LeafValues &values, const openvdb::tree::LeafManager<const openvdb::BoolTree> &leaves,
                 openvdb::Int32Tree &at) {
    for (std::size_t l = 0; l < leaves.leafCount(); ++l)
        if (!values.emptyIn(l)) at.touchLeaf(leaves.leaf(l).origin());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            if (values.emptyIn(l)) continue;
            openvdb::Int32Tree::LeafNodeType &leaf = *at.probeLeaf(leaves.leaf(l).origin());
            values.forEachIn(l, [&](std::size_t k) { leaf.setValueOnly(values.values[k].first, std::int32_t(k)); });
        }
    });
}

// Whether voxel c is a corner of a cell where the trilinear density can be non-zero: elsewhere the gathering
// reads no value (bakedRadianceAlong skips samples without snow).
bool besideSnow(Medium::Accessor &density, const openvdb::Coord &c) {
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz)
                if (density.getValue(c.offsetBy(dx, dy, dz)) > 0.0f) return true;
    return false;
}

// Grid k < 4 of BakedGrids' value from a broad lobe: l0, then l1's x, y and z (RGB).
openvdb::Vec3f broadComponent(const BroadLobe &S, int k) {
    return k == 0 ? openvdb::Vec3f(S.l0.x, S.l0.y, S.l0.z) : openvdb::Vec3f(S.l1[0][k - 1], S.l1[1][k - 1], S.l1[2][k - 1]);
}

// Grid k of BakedGrids' value from a source function: the broad lobe's four, then the peaked lobe's p0 and p1.
openvdb::Vec3f sourceComponent(const Source &S, int k) {
    return k < 4 ? broadComponent(S, k) : k == 4 ? openvdb::Vec3f(S.peak0.x, S.peak0.y, S.peak0.z)
                                                 : openvdb::Vec3f(S.peak1.x, S.peak1.y, S.peak1.z);
}

// The grids' values (BakedGrids::Values) of a source function.
BakedGrids::Values sourceComponents(const Source &S) {
    BakedGrids::Values out;
    for (int k = 0; k < int(BakedGrids::kCount); ++k) out[k] = sourceComponent(S, k);
    return out;
}

// The on-states of a voxel mask within `radius` (at most 4) of voxel c, read from the at most eight leaves that
// hold them (found once) instead of looked up voxel by voxel.
class BlockMask {
  public:
    BlockMask(openvdb::tree::ValueAccessor<const openvdb::BoolTree> &mask, const openvdb::Coord &c, int radius)
        : split_(((c.x() - radius) & ~7) + 8, ((c.y() - radius) & ~7) + 8, ((c.z() - radius) & ~7) + 8) {
        for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b)
                for (int d = 0; d < 2; ++d)
                    leaves_[a][b][d] = mask.probeConstLeaf(split_.offsetBy(8 * a - 8, 8 * b - 8, 8 * d - 8));
    }
    bool isOn(const openvdb::Coord &v) const {  // v within the radius of c
        const openvdb::BoolTree::LeafNodeType *leaf =
            leaves_[v.x() >= split_.x()][v.y() >= split_.y()][v.z() >= split_.z()];
        return leaf && leaf->isValueOn(v);
    }

  private:
    openvdb::Coord split_;  // the upper leaves' origin
    const openvdb::BoolTree::LeafNodeType *leaves_[2][2][2];
};

// The returned grazing sun carried through the density ramp: voxel c (outside the unknowns, carrying its surface's
// radiance) in front of smooth surface voxels within two voxels whose peaked lobe (the sun returned sharply
// forwards, Method 5) travels towards it takes their peaked lobes where these are over twice its own (elsewhere
// its surface holds as much: a march towards the suns saved), weighted by the cosine squared between a lobe's
// axis and the way to c and by how much its surface faces c, in the share of the suns' light that reaches c
// uncollided (sunlit). On a lit rim seen against the sun the camera ray crosses the ramp at the
// top and becomes opaque in its camera side, whose own surface voxels take the sun at grazing incidence and
// hold little peak (mu0 0-0.2), while the light there is the lit top's forward return travelling through
// (ball_issue's top row: the reference's source 0.3-0.4 in the ramp's first optical depth, the bake's 0.15-0.2;
// ball_grey's top row seen against the sun -55 -> -37 %). Not across sharp edges (a peak whose way to c passes
// an edge voxel: their faces' light leaves face by face; slab_thick 4.4 -> 4.7 % with them, and left out
// wherever an edge voxel lay beside c, ball_issue's side rims seen against the sun stayed at -59 %), nor from
// traced voxels (their peak is their own beams' scattering). bench/bake_suite.py: docs/bake.md, Accuracy.
//
// peaks: the surface voxels holding a peaked lobe, read from the at most eight leaves around c (BlockMask): an
// index lookup for each of the 124 voxels around c took most of this walk's time.
void forwardPeakThrough(const Scene &scene, const SnowTopology &topo, const openvdb::Coord &c,
                        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index,
                        TracedIndex &tracedIndex, const SourceValues &source,
                        openvdb::tree::ValueAccessor<const openvdb::BoolTree> &peaks, Medium::ColumnMarcher &marcher,
                        Source &S) {
    struct Offset {
        openvdb::Coord from;  // c minus the way to c
        glm::dvec3 towards;   // unit
        bool beside;          // within one voxel
        openvdb::Coord lo, hi;  // the voxels around the midpoint of the way, from `from`
    };
    static const std::vector<Offset> offsets = [] {
        const auto half = [](int v, bool up) { return int(up ? std::ceil(v / 2.0) : std::floor(v / 2.0)); };
        std::vector<Offset> out;
        for (int dx = -2; dx <= 2; ++dx)
            for (int dy = -2; dy <= 2; ++dy)
                for (int dz = -2; dz <= 2; ++dz)
                    if (dx || dy || dz)
                        out.push_back({openvdb::Coord(-dx, -dy, -dz), glm::normalize(glm::dvec3(dx, dy, dz)),
                                       std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) == 1,
                                       openvdb::Coord(half(dx, false), half(dy, false), half(dz, false)),
                                       openvdb::Coord(half(dx, true), half(dy, true), half(dz, true))});
        return out;
    }();
    const auto sharpAt = [&](const openvdb::Coord &v) {
        const std::int32_t k = index.getValue(v);
        return k >= 0 && topo.patches[k].sharp;
    };
    const BlockMask peakAt(peaks, c, 2);
    glm::dvec3 p0(0.0), p1(0.0);
    double total = 0.0;
    for (const Offset &o : offsets) {
        const openvdb::Coord from = c + o.from;
        if (!peakAt.isOn(from)) continue;
        const std::int32_t j = index.getValue(from);
        if (!o.beside && (sharpAt(from + o.lo) || sharpAt(from + o.hi))) continue;  // its light passes an edge
        const double facing = glm::dot(topo.patches[j].normal, o.towards);
        if (facing <= 0.0 || tracedIndex.getValue(from) >= 0) continue;
        const Source v = source[j];
        const double along = glm::dot(glm::normalize(glm::dvec3(v.peak1)), o.towards);
        if (along <= 0.0) continue;
        const double w = along * along * facing;
        p0 += w * glm::dvec3(v.peak0), p1 += w * glm::dvec3(v.peak1), total += w;
    }
    if (!(total > 0.0) || (p0.x + p0.y + p0.z) / total <= 2.0 * double(S.peak0.x + S.peak0.y + S.peak0.z)) return;
    const Medium &medium = *scene.medium;
    const glm::dvec3 centre = medium.voxelCentre(c);
    double arriving = 0.0, outside = 0.0;
    for (std::size_t b = 0; b < scene.suns.size(); ++b) {
        arriving += beamAt(scene, b, centre, 1, 0, 0, marcher, nullptr, Crossing::Uncollided).irradiance.y;
        outside += scene.suns[b].irradiance.y;
    }
    // The lit top's forward return crosses the ramp on a rim's camera side though the sun reaches it only through
    // the top's own snow: the sun's transmittance to c is delta-scaled by the share scattering keeps going forwards
    // (delta-Eddington: f = g^2, extinction sigma_t (1 - omega f)). ball_issue's view against the sun -27 -> -20 %;
    // with f = g -17 %, but ball_clean's (5 mm voxels of optical depth 30) -0 -> +4 % (branch seen-sun).
    const VolumeOptics &optics = scene.medium->optics();
    const double forwardKept = optics.albedo.y * optics.g * optics.g;
    const double lit = outside > 0.0 ? std::pow(arriving / outside, 1.0 - forwardKept) : 0.0;
    S.peak0 = glm::vec3(lit * p0 / total + (1.0 - lit) * glm::dvec3(S.peak0));
    S.peak1 = glm::vec3(lit * p1 / total + (1.0 - lit) * glm::dvec3(S.peak1));
}

// What the source grids hold, worked out once so that the grids can be written one at a time (a grid at
// the density's resolution takes 12 bytes for every voxel of its leaves: the four of one lobe took ~250 bytes per unknown on
// the car sample, docs/bake.md Memory).
// Over the snow's voxels and a margin of three: unknowns hold their source function. Outside them (the
// density ramp and surface fringes) the radiance of the nearest surface voxels is carried out two voxels, so
// the renderer's trilinear ramp sees a constant ratio of emission to extinction; voxels too thin for the
// solve, away from any surface, hold their single scattering; the outermost ring holds zeros (Cycles reads
// Vec3 grids' edges wrongly).
struct GridValues {
    openvdb::BoolTree::Ptr topology;  // the snow's voxels and the margin
    // Voxels other than the unknowns (traced unknowns among them), leaf by leaf: those holding a surface's
    // radiance or a traced source, then those one voxel further out and thin snow on its own.
    std::optional<LeafValues> beyond;
    openvdb::Int32Tree::Ptr at;  // voxel -> its place in beyond, -1 elsewhere
};

// gathering: the values the gathering reads alone (those beside snow, besideSnow: the grids carry the surface's
// radiance two voxels out, the gathering needs one), without the returned grazing sun carried through the ramp
// (forwardPeakThrough: what cameras see of a lit rim; the sky rays between snow surfaces hardly meet it, and it
// cost the car 0.8 processor seconds there).
GridValues gridValues(const Scene &scene, const SnowTopology &topo, const SourceValues &source,
                      const MonteCarloVoxels &traced, const Preset &preset, const BakeSettings &settings,
                      bool gathering) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    GridValues out;
    out.topology = std::make_shared<openvdb::BoolTree>(medium.density().tree(), false, openvdb::TopologyCopy());
    openvdb::tools::dilateActiveValues(*out.topology, 3, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    openvdb::tree::LeafManager<const openvdb::BoolTree> leaves(*out.topology);
    using Pairs = std::vector<VoxelValues>;

    // Average of the 26 neighbours accepted by `take`, read by `value`; false if none.
    auto average = [](const openvdb::Coord &c, const auto &take, const auto &value, Source &S) {
        int count = 0;
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const openvdb::Coord n = c.offsetBy(dx, dy, dz);
                    if (!take(n)) continue;
                    const Source v = value(n);
                    S.l0 += v.l0, S.l1 += v.l1, S.peak0 += v.peak0, S.peak1 += v.peak1, ++count;
                }
        if (count) S.l0 /= double(count), S.l1 /= double(count), S.peak0 /= double(count), S.peak1 /= double(count);
        return count > 0;
    };
    // Where forwardPeakThrough may find a peak: within two voxels of a smooth surface voxel holding one (the car's
    // grids took 4.6 processor seconds searching around every voxel next to a surface voxel, 4.3-4.4 so, 3.3 without).
    // peaks: smooth surface voxels holding a peaked lobe. A sharp edge's peak (its faces' grazing sun) stays its
    // own: carried through the ramp too, ball_issue's view against the sun read -29 % (-27 % without).
    openvdb::BoolTree nearPeak(false), peaks(false);
    if (!gathering) {
        std::vector<bool> peaked(source.broad.size(), false);  // by unknown
        for (const PeakedLobes::Peak &peak : source.peaked.peaks())
            peaked[peak.key] = glm::length(peak.peak1) > 0.0f;
        for (auto it = topo.index->cbeginValueOn(); it; ++it)
            if (const std::int32_t j = *it; j >= 0 && peaked[j] && topo.patches[j].isSurface() && !topo.patches[j].sharp)
                peaks.setValueOn(it.getCoord());
        nearPeak.topologyUnion(peaks);
        openvdb::tools::dilateActiveValues(nearPeak, 2, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                           openvdb::tools::IGNORE_TILES);
    }
    // Where facingAverage can find a surface voxel (within one voxel of one) and, beyond that, where a voxel can
    // have a carried neighbour (within one of those or of a traced voxel): elsewhere neither looks at 26
    // neighbours (the car's 3 M voxels of margin and fringe took 78 M lookups for 0.8 M values).
    openvdb::BoolTree nearSurface(*topo.index, false, openvdb::TopologyCopy());
    openvdb::tree::LeafManager<openvdb::BoolTree>(nearSurface).foreach([&](openvdb::BoolTree::LeafNodeType &leaf, std::size_t) {
        const auto &indexLeaf = *topo.index->probeConstLeaf(leaf.origin());
        for (auto it = leaf.beginValueOn(); it; ++it)
            if (!topo.patches[std::size_t(indexLeaf.getValue(it.pos()))].isSurface()) it.setValueOff();
    });
    openvdb::tools::dilateActiveValues(nearSurface, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    openvdb::BoolTree nearCarried(nearSurface);
    nearCarried.topologyUnion(*traced.index);
    openvdb::tools::dilateActiveValues(nearCarried, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    // First: traced voxels, and the voxels next to surface voxels (unknowns hold their own source).
    Pairs perLeaf(leaves.leafCount());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        TracedIndex tracedIndex(traced);
        openvdb::tree::ValueAccessor<const openvdb::BoolTree> nearPeakAt(nearPeak), peaksAt(peaks), nearSurfaceAt(nearSurface);
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t l = range.begin(); l != range.end(); ++l)
            for (auto it = leaves.leaf(l).cbeginValueOn(); it; ++it) {
                const openvdb::Coord c = it.getCoord();
                const std::int32_t t = tracedIndex.getValue(c);
                Source S;
                if (t >= 0) S = traced.source[t];
                else if (!nearSurfaceAt.isValueOn(c) || index.getValue(c) >= 0) continue;
                else if (faceCarried(c, tracedIndex, traced, S)) {}
                else if (!facingAverage(topo, c, index, source, S)) continue;
                else if (nearPeakAt.isValueOn(c))
                    forwardPeakThrough(scene, topo, c, index, tracedIndex, source, peaksAt, marcher, S);
                perLeaf[l].add(it.pos(), S);
            }
    });
    // The second block adds at most a value per voxel near the carried ones or holding snow.
    LeafValues carried(std::move(perLeaf), nearCarried.activeVoxelCount() + medium.density().activeVoxelCount());
    out.at = std::make_shared<openvdb::Int32Tree>(-1);
    placeValues(carried, leaves, *out.at);
    // Then: one voxel further out, and thin snow on its own.
    perLeaf = Pairs(leaves.leafCount());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> carriedSlot(*out.at);
        TracedIndex tracedIndex(traced);
        openvdb::tree::ValueAccessor<const openvdb::BoolTree> nearCarriedAt(nearCarried);
        Medium::Accessor density = medium.accessor();
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t l = range.begin(); l != range.end(); ++l)
            for (auto it = leaves.leaf(l).cbeginValueOn(); it; ++it) {
                const openvdb::Coord c = it.getCoord();
                if (index.getValue(c) >= 0 || carriedSlot.getValue(c) >= 0) continue;
                const bool mayBeNear = nearCarriedAt.isValueOn(c), snow = density.getValue(c) > 0.0f;
                if (!mayBeNear && !snow) continue;  // no value
                if (gathering && !snow && !besideSnow(density, c)) continue;
                Source S;
                const bool near = mayBeNear && average(c, [&](const openvdb::Coord &n) {
                    return carriedSlot.getValue(n) >= 0 && (index.getValue(n) < 0 || tracedIndex.getValue(n) >= 0); },
                                          [&](const openvdb::Coord &n) { return carried[carriedSlot.getValue(n)]; },
                                          S);
                if (!near && snow) {
                    const glm::dvec3 centre = medium.voxelCentre(c);
                    for (std::size_t b = 0; b < beamCount(scene); ++b) {
                        const glm::dvec3 beam = glm::dvec3(beamAt(scene, b, centre, preset.sunSamples, settings.seed,
                                                                  std::uint64_t(l), marcher).irradiance) *
                                                optics.albedo * kInvFourPi;
                        S.addPeak(beam, crossingAnisotropy(optics.g), -towardsBeam(scene, b, centre));
                    }
                }
                if (near || snow) perLeaf[l].add(it.pos(), S);
            }
    });
    out.beyond.emplace(std::move(carried), std::move(perLeaf));
    placeValues(*out.beyond, leaves, *out.at);
    return out;
}

// Grid k of BakedGrids (l0, then l1's x, y and z) at the density's resolution.
openvdb::Vec3fTree::Ptr sourceTree(const GridValues &values, const SnowTopology &topo, const SourceValues &source,
                                   const MonteCarloVoxels &traced, int k) {
    auto tree = std::make_shared<openvdb::Vec3fTree>(*values.topology, openvdb::Vec3f(0.0f), openvdb::TopologyCopy());
    openvdb::tree::LeafManager<openvdb::Vec3fTree> leaves(*tree);  // in the topology's leaf order
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        TracedIndex tracedIndex(traced);
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            auto &leaf = leaves.leaf(l);
            for (auto it = leaf.beginValueOn(); it; ++it) {
                const openvdb::Coord c = it.getCoord();
                if (const std::int32_t i = index.getValue(c); i >= 0 && tracedIndex.getValue(c) < 0)
                    it.setValue(k < 4 ? broadComponent(source.broad[i], k) : sourceComponent(source[i], k));
            }
            const LeafValues &beyond = *values.beyond;
            beyond.forEachIn(l, [&](std::size_t m) {
                leaf.setValueOnly(beyond.values[m].first, k < 4 ? broadComponent(beyond.values[m].second, k)
                                                                : sourceComponent(beyond[m], k));
            });
        }
    });
    return tree;
}

// Grid k of BakedGrids from its tree, `scale` times the voxel size of `density`, for optics of extinction
// `extinctionPerDensity` (m^2/kg).
openvdb::Vec3fGrid::Ptr sourceGrid(openvdb::Vec3fTree::Ptr tree, int k, int scale, const openvdb::FloatGrid &density,
                                   double extinctionPerDensity, const BakeSettings &settings) {
    auto grid = openvdb::Vec3fGrid::create(std::move(tree));
    grid->setTransform(density.transform().copy());
    if (scale > 1) grid->transform().preScale(double(scale));
    grid->setName(BakedGrids::kNames[k]);
    grid->setVectorType(openvdb::VEC_INVARIANT);
    grid->insertMeta("firn_units", openvdb::StringMetadata("W/m^2/sr (source function: emission / extinction)"));
    grid->insertMeta("firn_extinction_per_density", openvdb::DoubleMetadata(extinctionPerDensity));
    grid->insertMeta("firn_bake_quality",
                     openvdb::StringMetadata(settings.quality == BakeQuality::Draft   ? "DRAFT"
                                             : settings.quality == BakeQuality::Final ? "FINAL"
                                                                                      : "REFERENCE"));
    grid->insertMeta("firn_bake_seed", openvdb::Int64Metadata(openvdb::Int64(settings.seed)));
    grid->insertMeta("firn_version", openvdb::StringMetadata(kVersion));
    return grid;
}

// BakedGrids' values at a point of the density's index space before the grids are written: read from the
// unknowns' source and the values beyond them, trilinear as BoxSampler reads a grid (the same values, bit for
// bit). The last cell's corners are kept: the gathering's half-voxel steps read each cell about twice. One per
// thread.
class BakedValuesSampler {
  public:
    BakedValuesSampler(const SnowTopology &topo, const SourceValues &source, const MonteCarloVoxels &traced,
                       const GridValues &values)
        : source_(source), beyond_(*values.beyond), index_(*topo.index), traced_(traced), at_(*values.at) {}

    BakedGrids::Values operator()(const openvdb::Vec3d &ijk) {
        const openvdb::Coord lower = floorCoord(ijk);
        if (!cached_ || lower != cell_) {
            for (int a = 0; a < 2; ++a)
                for (int b = 0; b < 2; ++b)
                    for (int c = 0; c < 2; ++c) {
                        const Source S = at(lower.offsetBy(a, b, c));
                        for (int g = 0; g < int(BakedGrids::kCount); ++g) corners_[g][a][b][c] = sourceComponent(S, g);
                    }
            cell_ = lower, cached_ = true;
        }
        const openvdb::Vec3R uvw = ijk - lower.asVec3d();
        BakedGrids::Values out;
        for (int g = 0; g < int(BakedGrids::kCount); ++g)
            out[g] = openvdb::tools::BoxSampler::trilinearInterpolation(corners_[g], uvw);
        return out;
    }

    // The value at voxel c (what the grids hold there at the density's resolution).
    Source at(const openvdb::Coord &c) {
        if (const std::int32_t i = index_.getValue(c); i >= 0 && traced_.getValue(c) < 0) return source_[i];
        const std::int32_t k = at_.getValue(c);
        return k >= 0 ? beyond_[k] : Source{};
    }

  private:
    const SourceValues &source_;
    const LeafValues &beyond_;
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index_;
    TracedIndex traced_;
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> at_;
    bool cached_ = false;
    openvdb::Coord cell_;  // the cell whose corners corners_ holds
    openvdb::Vec3f corners_[BakedGrids::kCount][2][2][2];
};

// The source grids at `scale` times the density's voxel size. At the density's resolution each grid is built
// before the next; coarser, all six are coarsened together from the values directly (coarsenedSources), none
// built at the density's resolution.
BakedGrids makeGrids(const Scene &scene, const SnowTopology &topo, const SourceValues &source,
                     const MonteCarloVoxels &traced, const Preset &preset, const BakeSettings &settings, int scale) {
    GridValues values = gridValues(scene, topo, source, traced, preset, settings, false);
    BakedGrids out;
    if (scale == 1) {
        values.at = nullptr;  // only the coarsening's readers (BakedValuesSampler) read it
        for (int k = 0; k < int(BakedGrids::kCount); ++k)
            out.source[k] = sourceGrid(sourceTree(values, topo, source, traced, k), k, scale, scene.medium->density(),
                                       scene.medium->optics().extinctionPerDensity, settings);
        return out;
    }
    const auto newReader = [&] {
        return [baked = std::make_shared<BakedValuesSampler>(topo, source, traced, values)](const openvdb::Coord &c) {
            return sourceComponents(baked->at(c));
        };
    };
    auto trees = coarsenedSources(*values.topology, newReader, scene.medium->density().tree(), scale);
    for (int k = 0; k < int(BakedGrids::kCount); ++k)
        out.source[k] = sourceGrid(std::move(trees[k]), k, scale, scene.medium->density(),
                                   scene.medium->optics().extinctionPerDensity, settings);
    return out;
}

// Light that surface voxels receive from other snow across the air (a valley between bumps, the inside
// of a hollow): the baked snow's radiance along the sky rays that snow hides (W/m^2 onto each patch), read
// from the bake's values as its grids would hold them.
SurfaceValues<glm::vec3> snowIrradiance(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                                      const SourceValues &source, const MonteCarloVoxels &traced,
                                      const GridValues &values, const SkyRays &rays, std::uint64_t seed,
                                      const SubProgress &progress, SurfaceValues<glm::vec3> &aim) {
    SurfaceValues<glm::vec3> out(topo.surfaceSlot, topo.surfaceVoxels(), glm::vec3(0.0f));
    aim = out;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 256), [&](const auto &range) {
        progress.throwIfCancelled();
        Medium::ColumnMarcher marcher(*scene.medium);
        Medium::Accessor density = scene.medium->accessor();
        BakedValuesSampler baked(topo, source, traced, values);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!light.snowRays[i]) continue;
            const glm::dvec3 p = patchOutside(*scene.medium, topo, i, density);
            glm::dvec3 sum(0.0), towards(0.0);
            for (int k = 0; k < rays.count(); ++k) {
                if (!(light.snowRays[i] >> k & 1)) continue;
                const glm::dvec3 w = rays.direction(topo.patches[i].normal, k, seed, i);
                const auto hit = scene.occluders->caster().intersect(glm::vec3(p), glm::vec3(w), 1e-5f);
                const double tMax = hit ? double(hit->distance) : std::numeric_limits<double>::infinity();
                const glm::dvec3 radiance = bakedRadianceAlong(scene, marcher, baked, Ray{p, w}, tMax, 0.5);
                sum += radiance, towards += (radiance.x + radiance.y + radiance.z) / 3.0 * w;
            }
            out.surface(i) = glm::vec3(kPi * sum / double(rays.count()));  // snowRays: a surface voxel
            aim.surface(i) = glm::vec3(kPi * towards / double(rays.count()));
        }
    });
    return out;
}

}  // namespace

namespace {

// The finest source grids whose dense box fits Cycles' budget (kSourceBudgetBytes): a small object keeps the
// density's resolution, a street's snow gets coarser light (its dense box would not fit in memory).
int sourceScaleFor(const Medium &medium, const BakeSettings &settings) {
    if (settings.sourceScale > 0) return settings.sourceScale;
    const openvdb::Coord extent = medium.density().evalActiveVoxelBoundingBox().dim();
    const double boxVoxels = double(extent.x() + 6) * double(extent.y() + 6) * double(extent.z() + 6);  // + extension, ring
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

// Progress when the diffusion solves are done (REFERENCE: before path tracing the surface).
constexpr double kSolvedProgress = 0.9, kSolvedProgressReference = 0.5;

// The source function of every unknown: per pass (the later ones gather the light between snow surfaces
// first), a diffusion solve per channel. One channel at a time, its system assembled and its solver built
// again each pass: keeping the three tripled the bake's memory, and rebuilding them costs a few per cent of a
// solve. All the solve's data is freed on return, before the grids are written.
SourceValues solveSources(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                                 const MonteCarloVoxels &traced, const Preset &preset, const BakeSettings &settings,
                                 int passes, bool bounceTail, Progress &p, Stopwatch &clock, BakeStats &stats) {
    const bool reference = settings.quality == BakeQuality::Reference;
    const double solved = reference ? kSolvedProgressReference : kSolvedProgress;
    std::array<std::vector<double>, 3> phi;  // each solve starts from the previous pass's solution
    for (auto &channel : phi) channel.assign(topo.size(), 0.0);
    SurfaceValues<glm::vec3> fromSnow;  // W/m^2 gathered from other snow onto surface patches (after the first pass)
    SurfaceValues<glm::vec3> fromSnowAim;  // its first moment over the directions it arrives from (grey)
    SurfaceValues<glm::vec3> before, older;  // the two gathers before it (bounceTail only)
    SourceValues source;
    for (int pass = 0; pass < passes; ++pass) {
        const double begin = 0.4 + (solved - 0.4) * pass / passes, end = 0.4 + (solved - 0.4) * (pass + 1) / passes;
        // A pass after the first gathers first: the first half of its progress, the three solves the rest.
        const double gathered = pass > 0 ? (begin + end) / 2.0 : begin;
        if (pass > 0) {
            // Snow lit by snow: gather the previous pass's radiance and solve again (one bounce a pass).
            p.report(begin, "Gathering light between snow surfaces");
            {
                const GridValues values = gridValues(scene, topo, source, traced, preset, settings, true);
                if (bounceTail) older = std::move(before), before = std::move(fromSnow);
                fromSnow = snowIrradiance(scene, topo, light, source, traced, values, SkyRays(preset.skySamples),
                                          settings.seed ^ 0x5C1Eull, SubProgress(&p, begin, gathered), fromSnowAim);
                if (preset.skyOverNeighbours) averageOverNeighbours(topo, fromSnow), averageOverNeighbours(topo, fromSnowAim);
                if (bounceTail && pass + 1 == passes && pass > 1) {
                    addBounceTail(topo, pass > 2 ? &older : nullptr, before, fromSnow);
                    older = before = SurfaceValues<glm::vec3>();
                }
                source = SourceValues();  // freed (= {} would keep its vectors' capacity)
            }
            releaseFreedMemory();  // the previous pass's values
            clock.lap(&BakeStats::Phases::gather);
        }
        SurfaceValues<SurfaceLight> leaving(topo.surfaceSlot, topo.surfaceVoxels());
        {
            // The pass's three solves in the same vectors (held no longer than the pass's solves: the source
            // function and the gathering come after).
            ChannelStorage storage;
            MultigridSolver::Workspace workspace;
            for (int c = 0; c < 3; ++c) {
                const SubProgress sub(&p, gathered + (end - gathered) * c / 3.0, gathered + (end - gathered) * (c + 1) / 3.0);
                p.report(gathered + (end - gathered) * c / 3.0, "Solving multiple scattering");
                ChannelSystem system = assemble(scene, topo, light, c, sub, std::move(storage));
                if (pass > 0) system.addDiffuse(fromSnow, c);
                system.releaseDiffuseTerms();
                if (pass == 0 && c > 0) phi[c] = phi[c - 1];  // albedos differ little between channels
                if (topo.size() > 0) {
                    MultigridSolver solver(std::move(system.A), std::move(system.remainder));
                    releaseFreedMemory();  // what building the hierarchy freed, before CG's vectors
                    // Passes before the last only feed the gathering between surfaces: 0.1 % will do.
                    const double tolerance = pass + 1 < passes ? std::max(preset.tolerance, 1e-3) : preset.tolerance;
                    const MultigridSolver::Result result =
                        solver.solve(std::move(system.b), phi[c], tolerance, 500, sub, &workspace);
                    stats.iterations[c] += result.iterations;
                    stats.relativeResidual[c] = result.relativeResidual;
                    if (c + 1 < 3) {
                        std::tie(storage.A, storage.remainder) = std::move(solver).release();
                        storage.b = std::move(workspace.spare);
                    }
                }
                surfaceLight(scene, topo, light, pass > 0 ? SnowLight{&fromSnow, &fromSnowAim} : SnowLight{}, system, phi[c],
                             c, leaving);
            }
        }
        SurfaceValues<Source> surface = surfaceRadiance(scene.medium->optics(), topo, leaving);
        if (reference && pass + 1 == passes) {
            p.report(solved, "Path tracing the surface (reference)");
            referenceSurface(scene, topo, preset.referenceSamples, settings.seed, surface, SubProgress(&p, solved, 0.95));
        }
        source = sourceFunction(scene, topo, light, phi, surface, traced);
        clock.lap(&BakeStats::Phases::solve);
    }
    return source;
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
    MonteCarloVoxels traced;
    ThreadSeconds tracing;
    runBeside(
        [&] {
            light = computeIncidentLight(
                scene, topo, {preset.skySamples, preset.sunSamples, settings.seed, preset.skyOverNeighbours},
                beside.step(0));
        },
        [&] {
            tracing = isolatedOnThisThread([&] {
                const SubProgress progress = beside.step(1);
                TracedSnow snow = thinVoxels(*scene.medium, topo);
                thin = std::move(snow.thin);
                if (!snow.wholePieces.empty()) {  // transport-thin pieces: light traced whole, else as before
                    std::vector<openvdb::Coord> whole = thin;
                    whole.insert(whole.end(), snow.wholePieces.begin(), snow.wholePieces.end());
                    traced = lightTraceSources(scene, whole, settings.seed ^ 0x7EACEull, progress, local, kWholePieceTracedSteps);
                    if (!traced.source.empty()) thin = std::move(whole);
                }
                if (traced.source.empty()) {
                    const GatheringPlan plan = planGathering(scene, preset, thin, settings.seed ^ 0x7EACEull);
                    traced = lightTracedAtGatheringCost(scene, thin, plan, settings.seed ^ 0x7EACEull, progress, local);
                    if (traced.source.empty()) {
                        local.tracedPaths = plan.paths;
                        traced = plan.paths > 0 || thin.empty()
                                     ? traceSources(scene, thin, plan.paths, settings.seed ^ 0x7EACEull, progress)
                                     : lightTraceSources(scene, thin, settings.seed ^ 0x7EACEull, progress, local);
                        if (plan.paths > 0) addFaceSources(scene, topo, thin, plan, settings.seed ^ 0xFACEull, traced);
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
    const std::vector<std::uint64_t> &snowRays = light.snowRays.values();
    const bool hidden = std::any_of(snowRays.begin(), snowRays.end(), [](std::uint64_t r) { return r != 0; });
    // Small pieces and thin snow left to the diffusion (too many to trace: a skier's thousands of lumps) light
    // each other over many bounces: one more gather, and the rest of the bounces from the last two (addBounceTail).
    const bool untracedPieces = !thin.empty() && traced.source.empty();
    const int passes = local.passes = hidden ? 1 + preset.snowBounces + (untracedPieces ? 1 : 0) : 1;
    const SourceValues source =
        solveSources(scene, topo, light, traced, preset, settings, passes, untracedPieces, p, clock, local);
    light = IncidentLight{};  // the grids need it no more
    keepIndexAndPatches(topo);
    p.report(reference ? 0.95 : kSolvedProgress, "Writing the grids");
    BakedGrids grids = makeGrids(scene, topo, source, traced, preset, settings, sourceScale);
    local.sourceScale = sourceScale;
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
