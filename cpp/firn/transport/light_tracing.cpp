#include "firn/transport/light_tracing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <utility>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/outside_share.h"
#include "firn/transport/pooled_estimates.h"
#include "firn/transport/traced_source.h"
#include "firn/util/color.h"
#include "firn/util/sampling.h"
#include "firn/util/work_check.h"

namespace firn {

namespace {

constexpr long kPhotonsPerChunk = 1024;  // the unit of reduction: sums add in chunk order
constexpr long kChunksPerBatch = 16;     // traced in parallel between reductions (bounds the chunks' sums held)
constexpr double kSurfaceEpsilon = 1e-5;  // m: shadow rays leaving a face of the box start this far off it
constexpr std::uint64_t kBeamSeed = 0xBEA3ull;  // the beams' streams apart from the photons'
constexpr std::uint64_t kOutsideSeed = 0x0C1Dull;  // outsideShare's points' streams
// A collision's sums cost about this many tracking steps (a 40 cm cloud of snow scattering hundreds of times: 2e8
// steps took 43 processor s with the sums, against 12 s per 2e8 steps without).
constexpr long kStepsPerTally = 4;
constexpr double kDiffuseShare = 0.25;    // of the photons at least: light the occluders reflect comes this way
// Voxels: the box photons enter and leave lies this far inside the medium's bounds, so that every occluder is
// either inside it (photons reflect off it) or outside (the light arriving through its faces holds the reflection).
// On the bounds themselves (a surface mesh on the voxels' lattice under resting lumps) an occluder counted both ways:
// +4 % in all, +60 % upward flux (LightTracing.MatchesGatheringOverAGroundOnItsBounds). Off the lattice's planes,
// and far above float rounding.
constexpr double kBoxInset = 0.0173;

struct Face {
    glm::dvec3 corner, u, v, inward;  // m; inward: unit
    double area;                      // m^2
};

std::array<Face, 6> boxFaces(const glm::dvec3 &lo, const glm::dvec3 &hi) {
    std::array<Face, 6> out;
    const glm::dvec3 size = hi - lo;
    for (int a = 0; a < 3; ++a) {
        glm::dvec3 u(0.0), v(0.0), n(0.0), far = lo;
        u[(a + 1) % 3] = size[(a + 1) % 3], v[(a + 2) % 3] = size[(a + 2) % 3], n[a] = 1.0, far[a] = hi[a];
        const double area = glm::length(u) * glm::length(v);
        out[2 * a] = Face{lo, u, v, n, area};
        out[2 * a + 1] = Face{far, u, v, -n, area};
    }
    return out;
}

// Photons entering the medium's bounding box through its faces: each sun's beam, and all other light arriving
// there. Their power is per photon of one: the sums are divided by the photons' number at the end.
class BoxEmitter {
  public:
    explicit BoxEmitter(const MonteCarloReference &reference)
        : reference_(reference),
          lo_(reference.scene().medium->boundsMin() + kBoxInset * reference.scene().medium->voxelSize()),
          hi_(reference.scene().medium->boundsMax() - kBoxInset * reference.scene().medium->voxelSize()),
          faces_(boxFaces(lo_, hi_)) {
        const Scene &scene = reference.scene();
        for (const Face &f : faces_) totalArea_ += f.area;
        // Shares by the power each brings in: a sun's irradiance over the box's cross-section, the sky's mean
        // radiance over pi times its area (the occluders' reflections not known yet: kDiffuseShare at least).
        std::vector<double> power;
        for (const SunLight &sun : scene.suns) power.push_back(channelMean(sun.irradiance) * crossSection(-sun.direction));
        double sky = 0.0;
        constexpr int kSkyDirections = 256;
        for (int i = 0; i < kSkyDirections; ++i) {  // a Fibonacci sphere
            const double z = 1.0 - (2.0 * i + 1.0) / kSkyDirections, r = std::sqrt(1.0 - z * z), phi = 2.399963229728653 * i;
            sky += channelMean(scene.sky.radianceFrom(glm::dvec3(r * std::cos(phi), r * std::sin(phi), z))) / kSkyDirections;
        }
        double total = kPi * totalArea_ * sky;
        for (double p : power) total += p;
        diffuseShare_ = total > 0.0 ? std::max(kDiffuseShare, kPi * totalArea_ * sky / total) : 1.0;
        for (double p : power) sunShare_.push_back(total > 0.0 ? (1.0 - diffuseShare_) * p / (total - kPi * totalArea_ * sky) : 0.0);
    }

    // One photon (zero power where no light comes), `tracer` finding its radiance.
    Photon emit(Rng &rng, PhotonTracer &tracer) const {
        double u = rng.uniform();
        for (std::size_t b = 0; b < sunShare_.size(); ++b) {
            if (u < sunShare_[b]) return sunPhoton(reference_.scene().suns[b], sunShare_[b], rng);
            u -= sunShare_[b];
        }
        return diffusePhoton(rng, tracer);
    }

    // The box photons enter and leave.
    const glm::dvec3 &boxMin() const { return lo_; }
    const glm::dvec3 &boxMax() const { return hi_; }

  private:
    // The box's area seen along `travel`.
    double crossSection(const glm::dvec3 &travel) const {
        double sum = 0.0;
        for (const Face &f : faces_) sum += f.area * std::max(0.0, glm::dot(f.inward, travel));
        return sum;
    }

    static glm::dvec3 pointOn(const Face &f, Rng &rng) { return f.corner + rng.uniform() * f.u + rng.uniform() * f.v; }

    // A sun's beam through a face that sees the sun, faces drawn by their cross-section.
    Photon sunPhoton(const SunLight &sun, double share, Rng &rng) const {
        const glm::dvec3 towards = sampleSunDirection(sun, rng.uniform(), rng.uniform());
        const double across = crossSection(-towards);
        double pick = rng.uniform() * across;
        const Face *face = &faces_.back();
        for (const Face &f : faces_) {
            const double a = f.area * std::max(0.0, -glm::dot(f.inward, towards));
            if (a > 0.0 && pick < a) {
                face = &f;
                break;
            }
            pick -= a;
        }
        const glm::dvec3 p = pointOn(*face, rng);
        const Scene &scene = reference_.scene();
        if (scene.occluders->caster().occluded(glm::vec3(p), glm::vec3(towards), float(kSurfaceEpsilon)))
            return Photon{Ray{p, -towards}};
        return Photon{Ray{p, -towards}, sun.irradiance * (across / share), true};
    }

    // All other light arriving through a face: a cosine-weighted direction into the box, its radiance from one
    // path of the reference traced out of the box.
    Photon diffusePhoton(Rng &rng, PhotonTracer &tracer) const {
        double pick = rng.uniform() * totalArea_;
        const Face *face = &faces_.back();
        for (const Face &f : faces_) {
            if (pick < f.area) {
                face = &f;
                break;
            }
            pick -= f.area;
        }
        const glm::dvec3 p = pointOn(*face, rng);
        const glm::dvec3 d = sampleCosineHemisphere(face->inward, rng.uniform(), rng.uniform());
        // No light arrives inside a closed occluder (the box's faces under the snow's surface mesh the lumps rest
        // on): a photon of none, where its radiance's path would bounce inside until roulette (a sun's photon
        // there is shadowed by the occluder itself).
        if (tracer.enclosed(p)) return Photon{Ray{p, d}};
        const Rgb L = tracer.radianceArriving(Ray{p, -d}, rng);
        return Photon{Ray{p, d}, L * (kPi * totalArea_ / diffuseShare_)};
    }

    const MonteCarloReference &reference_;
    glm::dvec3 lo_, hi_;
    std::array<Face, 6> faces_;
    double totalArea_ = 0.0, diffuseShare_ = 1.0;
    std::vector<double> sunShare_;
};

// Per voxel: its index among the voxels a fit by direction follows (fittedByDirection: only theirs gather
// ArrivingToward), -1 for the others.
std::vector<std::int32_t> towardSlots(const Medium &medium, const std::vector<openvdb::Coord> &voxels) {
    std::vector<std::int32_t> out(voxels.size(), -1);
    Medium::Accessor density = medium.accessor();
    std::int32_t fitted = 0;
    for (std::size_t v = 0; v < voxels.size(); ++v)
        if (fittedByDirection(medium, density, voxels[v])) out[v] = fitted++;
    return out;
}

std::size_t fittedCount(const std::vector<std::int32_t> &towardSlot) {
    return std::size_t(std::count_if(towardSlot.begin(), towardSlot.end(), [](std::int32_t s) { return s >= 0; }));
}

// The voxels' sums: each voxel's ArrivingLight, and the ArrivingToward of those fitted by direction.
struct VoxelSums {
    VoxelSums(const Medium &medium, const std::vector<openvdb::Coord> &voxels)
        : light(voxels.size()), towardSlot(towardSlots(medium, voxels)),
          toward(fittedCount(towardSlot)) {}
    std::vector<ArrivingLight> light;      // per voxel
    std::vector<std::int32_t> towardSlot;  // towardSlots
    std::vector<ArrivingToward> toward;    // per voxel fitted by direction, in voxel order
};

// What one chunk of photons adds to the voxels' sums, each in index order.
struct ChunkSums {
    std::vector<std::pair<std::int32_t, ArrivingLight>> light;    // by voxel
    std::vector<std::pair<std::int32_t, ArrivingToward>> toward;  // by slot (VoxelSums::towardSlot)
};

template <class Sum>
std::vector<std::pair<std::int32_t, Sum>> inOrder(const std::unordered_map<std::int32_t, Sum> &sums) {
    std::vector<std::pair<std::int32_t, Sum>> out(sums.begin(), sums.end());
    std::sort(out.begin(), out.end(), [](const auto &a, const auto &b) { return a.first < b.first; });
    return out;
}

// The light photons [first, last) bring to the voxels (index >= 0; `towardSlot`: VoxelSums').
ChunkSums traceChunk(const MonteCarloReference &reference, const BoxEmitter &emitter, const openvdb::Int32Tree &index,
                     const std::vector<std::int32_t> &towardSlot, long first, long last, std::uint64_t seed,
                     long &steps, const SubProgress &progress) {
    const Medium &medium = *reference.scene().medium;
    const VolumeOptics &optics = medium.optics();
    const SourceDirections &directions = reference.directions();
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> voxelOf(index);
    std::unordered_map<std::int32_t, ArrivingLight> light;
    std::unordered_map<std::int32_t, ArrivingToward> toward;
    long tallies = 0;
    const CollisionTally tally = [&](const glm::dvec3 &p, const glm::dvec3 &travel, const Rgb &power) {
        const glm::dvec3 ijk = glm::round(medium.worldToIndex(p));
        const std::int32_t v = voxelOf.getValue(openvdb::Coord(int(ijk.x), int(ijk.y), int(ijk.z)));
        if (v < 0) return;
        light[v].add(power, travel, false, optics), ++tallies;
        if (const std::int32_t slot = towardSlot[std::size_t(v)]; slot >= 0) toward[slot].add(power, travel, optics, directions);
    };
    PhotonTracer tracer(reference);
    WorkCheck work(progress);  // a chunk's photons in dense snow: half a second of tracking steps
    for (long i = first; i < last; ++i) {
        Rng rng(seed, std::uint64_t(i));
        const long before = tracer.steps();
        const Photon photon = emitter.emit(rng, tracer);
        if (photon.power != Rgb(0.0)) tracer.follow(photon, emitter.boxMin(), emitter.boxMax(), rng, tally);
        work.add(std::uint64_t(tracer.steps() - before) + 1);
    }
    steps += tracer.steps() + kStepsPerTally * tallies;
    return ChunkSums{inOrder(light), inOrder(toward)};
}

// The voxel's integral of sigma_t (m^2): the trilinear density integrates over a voxel to weights 1/8, 3/4,
// 1/8 along each axis on the values at its neighbours' centres.
double extinctionIntegral(const Medium &medium, Medium::Accessor &density, const openvdb::Coord &c) {
    constexpr double w[3] = {0.125, 0.75, 0.125};
    double sum = 0.0;
    for (int i = 0; i < 27; ++i)
        sum += w[i % 3] * w[i / 3 % 3] * w[i / 9] * density.getValue(c.offsetBy(i % 3 - 1, i / 3 % 3 - 1, i / 9 - 1));
    const double h = medium.voxelSize();
    return medium.optics().extinctionPerDensity * sum * h * h * h;
}

// Voxel -> its index in `voxels`, -1 elsewhere.
openvdb::Int32Tree voxelIndex(const std::vector<openvdb::Coord> &voxels) {
    openvdb::Int32Tree index(-1);
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> set(index);
    for (std::size_t v = 0; v < voxels.size(); ++v) set.setValue(voxels[v], std::int32_t(v));
    return index;
}

}  // namespace

LightTracingPlan planLightTracing(const MonteCarloReference &reference, const std::vector<openvdb::Coord> &voxels,
                                  double maxSteps, std::uint64_t seed, double share) {
    // Fewer photons per voxel than kMinPhotonsPerVoxel and the lobes fitted to their noisy moments are biased
    // bright (the skier's lumps on 1 cm voxels, bench/spray_light_bench.py --dense: 10, 39, 280 photons per voxel
    // read 25.4, 18.2, 10.9 % per block, bias +15.2, +7.2, +6.8 %, where the diffusion gave 8.2 %, -2.2 %).
    constexpr long kPilotPhotons = 1024, kMinPhotons = 65536, kMaxPhotons = 100'000'000;
    constexpr double kMinPhotonsPerVoxel = 32.0;
    constexpr int kPilotVoxels = 64, kPilotSamples = 4, kMinBeamSamples = 4, kMaxBeamSamples = 64;
    constexpr double kBeamShare = 0.25;      // of the budget, for the beams' points at most
    constexpr double kStepsPerPhoton = 20.0;  // its start and its sums, in tracking steps
    // With occluders too (branch spray-trace; until then the diffusion kept these voxels wherever the scene had one):
    // the lumps of bench/spray_light_bench.py over the snow's surface mesh, over the gathering budget, read 33.7 %
    // per block, bias +26.7 % diffused and 8.9 %, +1.4 % light traced (seed 0; --dense 14.8 %, +13.5 % -> 10.9 %,
    // +8.2 %). Photons never start or count inside a closed occluder (BoxEmitter, outsideShare), as the gathering's
    // points (PathTracer::enclosed).
    LightTracingPlan plan;
    if (voxels.empty() || !reference.scene().lamps.empty()) return plan;
    const double budget = share * maxSteps;  // tracking steps
    double beamSteps = 0.0;
    for (int k = 0; k < kPilotVoxels; ++k) {
        const std::size_t v = voxels.size() * k / kPilotVoxels;
        beamSteps +=
            double(reference.sourceIn(voxels[v], kPilotSamples, seed ^ kBeamSeed, v, Gathering::BeamsOnly).steps);
    }
    const double perBeamSample = std::max(beamSteps / (kPilotVoxels * kPilotSamples), 1.0);
    plan.beamSamples = std::clamp(int(kBeamShare * budget / (perBeamSample * double(voxels.size()))),
                                  kMinBeamSamples, kMaxBeamSamples);
    // The pilot's photons in parallel pieces (its sums dropped); what the pilots cost comes out of the budget.
    constexpr long kPilotPieces = 8;
    const BoxEmitter emitter(reference);
    const openvdb::Int32Tree index = voxelIndex(voxels);
    const std::vector<std::int32_t> towardSlot = towardSlots(*reference.scene().medium, voxels);
    std::vector<long> pieceSteps(kPilotPieces, 0);
    tbb::parallel_for(tbb::blocked_range<long>(0, kPilotPieces, 1), [&](const auto &range) {
        for (long k = range.begin(); k != range.end(); ++k)
            traceChunk(reference, emitter, index, towardSlot, k * kPilotPhotons / kPilotPieces,
                       (k + 1) * kPilotPhotons / kPilotPieces, seed, pieceSteps[k], SubProgress(nullptr, 0.0, 1.0));
    });
    const double pilotSteps = double(std::accumulate(pieceSteps.begin(), pieceSteps.end(), 0L));
    const double perPhoton = pilotSteps / kPilotPhotons + kStepsPerPhoton;
    const double photonSteps = budget - beamSteps - pilotSteps - kStepsPerPhoton * kPilotPhotons -
                               perBeamSample * plan.beamSamples * double(voxels.size());
    plan.photons = long(std::min(double(kMaxPhotons), std::max(photonSteps, 0.0) / perPhoton));
    plan.sumsBytes = voxels.size() * (sizeof(ArrivingLight) + sizeof(std::int32_t)) + fittedCount(towardSlot) * sizeof(ArrivingToward);
    if (plan.photons < std::max(share * double(kMinPhotons), kMinPhotonsPerVoxel * double(voxels.size())))
        plan = LightTracingPlan{};
    return plan;
}

std::vector<SourceEstimate> lightTracedSources(const MonteCarloReference &reference,
                                               const std::vector<openvdb::Coord> &voxels,
                                               const LightTracingPlan &plan, std::uint64_t seed,
                                               const SubProgress &progress) {
    if (voxels.empty() || plan.photons <= 0) return {};
    const Medium &medium = *reference.scene().medium;
    const Occluders &occluders = *reference.scene().occluders;
    const openvdb::Int32Tree index = voxelIndex(voxels);
    const BoxEmitter emitter(reference);
    VoxelSums sums(medium, voxels);
    long steps = 0;
    const long chunks = (plan.photons + kPhotonsPerChunk - 1) / kPhotonsPerChunk;
    for (long first = 0; first < chunks; first += kChunksPerBatch) {
        progress.throwIfCancelled();
        const long last = std::min(chunks, first + kChunksPerBatch);
        std::vector<ChunkSums> batch(std::size_t(last - first));
        std::vector<long> batchSteps(batch.size(), 0);
        tbb::parallel_for(tbb::blocked_range<long>(first, last, 1), [&](const auto &range) {
            for (long c = range.begin(); c != range.end(); ++c)
                batch[c - first] = traceChunk(reference, emitter, index, sums.towardSlot, c * kPhotonsPerChunk,
                                              std::min(plan.photons, (c + 1) * kPhotonsPerChunk), seed,
                                              batchSteps[c - first], progress);
        });
        for (std::size_t c = 0; c < batch.size(); ++c) {
            for (const auto &[v, light] : batch[c].light) sums.light[v] += light;
            for (const auto &[slot, toward] : batch[c].toward) sums.toward[slot] += toward;
            steps += batchSteps[c];
        }
        progress.report(0.8 * double(last) / double(chunks));
    }
    // The photons' light: per photon, over the voxel's integral of sigma_t outside closed occluders, its source by
    // direction summed over a flat uniform layer (pooled_estimates.h); then each voxel's beams.
    std::vector<SourceEstimate> scattered(voxels.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 64), [&](const auto &range) {
        Medium::Accessor density = medium.accessor();
        PhotonTracer tracer(reference);
        WorkCheck work(progress);
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
            const long before = tracer.steps();
            const std::int32_t slot = sums.towardSlot[v];
            Rng rng(seed ^ kOutsideSeed, v);
            const double weights = double(plan.photons) * extinctionIntegral(medium, density, voxels[v]) *
                                   outsideShare(medium, density, occluders, tracer, voxels[v], rng);
            scattered[v] = sourceOf(sums.light[v], slot >= 0 ? &sums.toward[std::size_t(slot)] : nullptr, weights,
                                    medium.optics());
            work.add(WorkCheck::kVoxel + std::uint64_t(tracer.steps() - before));
        }
    });
    std::vector<SourceEstimate> out = pooledEstimates(medium, index, voxels, scattered);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 64), [&](const auto &range) {
        WorkCheck work(progress);
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
            const SourceEstimate beams =
                reference.sourceIn(voxels[v], plan.beamSamples, seed ^ kBeamSeed, v, Gathering::BeamsOnly);
            work.add(std::uint64_t(beams.steps) + 1);
            out[v] += beams;
        }
    });
    out.front().steps += steps;  // the photons' steps, counted once
    progress.report(1.0);
    return out;
}

}  // namespace firn
