#pragma once

// The source function of every unknown: the diffusion's inside, the surface's radiance, traced voxels.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/transport/bake_surface_light.h"
#include "firn/transport/bake_traced_voxels.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/transport/source_lobe.h"
#include "firn/util/progress.h"
#include "firn/util/unwritten_vector.h"

namespace firn::bake {

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
    using Peaks = UnwrittenVector<Peak>;
    const Peaks &peaks() const { return peaks_; }  // in key order
    static bool holds(const Source &S) { return S.peak0 != glm::vec3(0.0f) || S.peak1 != glm::vec3(0.0f); }
    // S's peak at `key` added to a block's list (keys in increasing order), where it holds one.
    static void append(Peaks &list, std::size_t key, const Source &S) {
        if (holds(S)) list.push_back({std::uint32_t(key), S.peak0, S.peak1});
    }
    // The blocks' peaks after these, block b's keys shifted by keyShift[b] (all keys in increasing order), with the
    // peaks copied and the bitmap's words worked out in parallel: the only way peaks come in (pushed one by one, the
    // car's 640,000 were a single-threaded step of its source function and its grids; docs/benchmarks.md, lead-81).
    void appendAll(const std::vector<const Peaks *> &blocks, const std::vector<std::size_t> &keyShift) {
        std::vector<std::size_t> at{peaks_.size()};
        for (const Peaks *block : blocks) at.push_back(at.back() + block->size());
        if (at.back() == at.front()) return;
        peaks_.resize(at.back());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 16), [&](const auto &range) {
            for (std::size_t b = range.begin(); b != range.end(); ++b)
                std::transform(blocks[b]->begin(), blocks[b]->end(), peaks_.begin() + at[b], [&](Peak peak) {
                    peak.key = std::uint32_t(peak.key + keyShift[b]);
                    return peak;
                });
        });
        indexWords(peaks_[at.front()].key / 64);
    }
    // One list's peaks after these, its keys as they are.
    void appendAll(const Peaks &list) { appendAll({&list}, {0}); }
    Peaks::const_iterator from(std::size_t key) const {  // the first peak of key >= key
        return std::lower_bound(peaks_.begin(), peaks_.end(), key,
                                [](const Peak &p, std::size_t k) { return p.key < k; });
    }
    // The source function of that broad lobe and key: its peak found by counting the keys held before it (a
    // binary search over the car's 640,000 peaks took 0.7 processor seconds of its gathering and grids).
    Source with(const BroadLobe &broad, std::size_t key) const {
        Source S;
        static_cast<BroadLobe &>(S) = broad;
        const std::size_t word = key / 64, bit = key % 64;
        if (word < held_.size() && (held_[word] >> bit & 1)) {
            const Peak &peak =
                peaks_[before_[word] + __builtin_popcountll(held_[word] & ((std::uint64_t(1) << bit) - 1))];
            S.peak0 = peak.peak0, S.peak1 = peak.peak1;
        }
        return S;
    }

  private:
    // held_ and before_ from word `first` on (it may hold earlier peaks too), read off the peaks.
    void indexWords(std::size_t first) {
        const std::size_t words = peaks_.back().key / 64 + 1;
        held_.resize(words), before_.resize(words);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(first, words, 4096), [&](const auto &range) {
            auto peak = from(64 * range.begin());
            for (std::size_t w = range.begin(); w != range.end(); ++w) {
                before_[w] = std::uint32_t(peak - peaks_.begin());
                std::uint64_t bits = 0;
                for (; peak != peaks_.end() && peak->key < 64 * (w + 1); ++peak)
                    bits |= std::uint64_t(1) << (peak->key % 64);
                held_[w] = bits;
            }
        });
    }
    Peaks peaks_;                        // in key order, added by appendAll() (the bitmap follows it)
    std::vector<std::uint64_t> held_;    // bit key % 64 of word key / 64: whether key holds a peak
    std::vector<std::uint32_t> before_;  // per word: the peaks of smaller keys
};

// The source function of every unknown.
struct SourceValues {
    UnwrittenVector<BroadLobe> broad;  // per unknown (sourceFunction writes them all)
    PeakedLobes peaked;                // by unknown
    // By surface voxel, with lamps alone: the part of its peaked lobe its ramp scatters itself (SurfaceLight).
    PeakedLobes rampPeaks;
    // The sharp edge voxels' flat faces' own lobes, carried by the air across each (SurfaceLight's; none at REFERENCE).
    EdgeFaceLobes edgeFaces;
    // By surface voxel, the share of its broad lobe the sky and other snow drive (skyShares; the peaked lobe is the
    // beams' alone); empty where the solves kept no beams apart.
    SurfaceValues<float> skyShare;

    Source operator[](std::size_t i) const { return peaked.with(broad[i], i); }
};

// Radiance leaving each surface voxel (its fitted lobe) from the solves' surface light.
SurfaceValues<Source> surfaceRadiance(const VolumeOptics &optics, const SnowTopology &topo,
                                      const SurfaceValues<SurfaceLight> &solved, const SubProgress &progress);

// Of each surface voxel's broad lobe (surfaceRadiance's `radiance`), the share the sky and other snow drive, read
// in green for the three channels (SurfaceLight::skyLeaving): its neighbourhood's exitance so driven over the whole,
// as surfaceRadiance averages it, less the crossing beams' part; the returned light's shape, which moves no exitance,
// is not split. Empty where the solves kept no beams apart (`apart` false).
SurfaceValues<float> skyShares(const SnowTopology &topo, const SurfaceValues<SurfaceLight> &solved,
                               const SurfaceValues<Source> &radiance, bool apart, const SubProgress &progress);

// The surface voxels' rampPeak0 and rampPeak1 (SourceValues::rampPeaks), where the scene has lamps: with suns alone
// beamsInRamp never reads them.
PeakedLobes rampPeaks(const Scene &scene, const SnowTopology &topo, const SurfaceValues<SurfaceLight> &solved);

// The source function of every unknown from the channels' fluence phi, the surface's radiance and the traced voxels.
SourceValues sourceFunction(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                            const std::array<UnwrittenVector<double>, 3> &phi, const SurfaceValues<Source> &surface,
                            const MonteCarloVoxels &traced, const SubProgress &progress);

// REFERENCE quality: the surface voxels' radiance path traced (`samples` paths a direction) into `out`.
void referenceSurface(const Scene &scene, const SnowTopology &topo, int samples, std::uint64_t seed,
                      SurfaceValues<Source> &out, const SubProgress &progress);

}  // namespace firn::bake
