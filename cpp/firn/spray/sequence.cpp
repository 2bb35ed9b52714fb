#include "firn/spray/sequence.h"

#include <algorithm>
#include <cmath>
#include <string>


#include "firn/spray/snow_level_set.h"
#include "firn/spray/spray_density.h"
#include "firn/util/error.h"

namespace firn {

namespace {

// The lumps of `ballsPerLump` balls that `ballsLeft` of the budget still holds (an infinite budget: 2^53, which no
// sub-step reaches; a double beyond a size_t's range does not convert).
std::size_t lumpsLeft(double ballsLeft, int ballsPerLump) {
    return std::size_t(std::clamp(std::floor(ballsLeft / ballsPerLump), 0.0, 9007199254740992.0));
}

// The balls the lumps could split into: the particle budget's worst case.
double ballCount(const SprayParticles &particles) {
    double balls = 0.0;
    for (const SprayParticle &p : particles) balls += p.ballCount;
    return balls;
}

bool outsideSnow(const openvdb::FloatGrid &surface, const glm::dvec3 &p) {
    return snowLevelSetAt(SnowSampler(surface), p) >= 0.0;
}

}  // namespace

void SpraySettings::validate() const {
    emission.validate();
    lumps.validate();
    flight.validate();
    tracks.validate();
    const auto check = [](bool ok, const char *what) {
        if (!ok) throw InvalidArgument(std::string("spray settings: ") + what);
    };
    check(substeps >= 1 && substeps <= 1000, "sub-steps per frame must be between 1 and 1000");
    check(voxelSize == 0.0 || (voxelSize >= 1e-4 && voxelSize < 100.0),
          "voxel size must be 0 (the snow's) or between 0.1 mm and 100 m");
    check(maxParticles >= 1.0, "the particle budget must be at least 1");
    check(maxVoxels >= 1.0 && maxVoxels <= kMaxVoxelBudget, "the voxel budget must be between 1 and 1e11 voxels");
}

void SprayScene::validate() const {
    if (emitters.empty()) throw InvalidArgument("spray needs at least one emitter");
    if (frameCount() < 2) throw InvalidArgument("spray needs the emitters' rectangles at two frames or more");
    for (std::size_t i = 0; i < emitters.size(); ++i) firn::validate(emitters[i], i, frameCount());
    if (!(fps > 0.0 && fps < 1e4)) throw InvalidArgument("frames per second must be between 0 and 10000");
}

SprayState initialSprayState(SnowGrids snow) {
    if (!snow.surface || !snow.density) throw InvalidArgument("spray needs the snow's density and surface grids");
    SprayState state;
    state.snow = std::move(snow);
    return state;
}

SprayFrameStats simulateSprayFrame(SprayState &state, const SprayScene &scene, const SpraySettings &s,
                                   const SubProgress &progress) {
    if (state.frame + 1 >= scene.frameCount())
        throw InvalidArgument("spray: frame " + std::to_string(state.frame + 1) + " is past the emitters' last frame");
    const double dt = 1.0 / (scene.fps * s.substeps);
    const std::uint64_t firstStep = std::uint64_t(state.frame) * std::uint64_t(s.substeps);
    SprayFrameStats stats;

    // The throws of every sub-step, from the snow as it was at the frame's start.
    std::vector<SprayParticles> thrown(s.substeps);
    double balls = ballCount(state.particles);
    for (int k = 0; k < s.substeps; ++k)
        for (std::size_t e = 0; e < scene.emitters.size(); ++e) {
            const Emitter &emitter = scene.emitters[e];
            const std::size_t budget = lumpsLeft(s.maxParticles - balls, s.lumps.ballsPerLump);
            SprayParticles lumps = emitLumps(emitterBetween(emitter, state.frame, double(k) / s.substeps),
                                             emitterBetween(emitter, state.frame, double(k + 1) / s.substeps), dt,
                                             *state.snow.surface, s.flight.down, s.emission, s.lumps, s.seed, e,
                                             firstStep + k, state.nextId, budget);
            balls += double(lumps.size()) * s.lumps.ballsPerLump;
            thrown[k].insert(thrown[k].end(), lumps.begin(), lumps.end());
        }
    progress.report(0.1);
    progress.throwIfCancelled();

    if (s.cutTracks)
        for (const Emitter &emitter : scene.emitters) {
            std::vector<EmitterRectangle> positions;
            for (int k = 0; k <= s.substeps; ++k)
                positions.push_back(emitterBetween(emitter, state.frame, double(k) / s.substeps));
            const TrackStats t = carveTrack(state.snow, positions, s.flight.down, s.tracks, s.maxVoxels);
            stats.tracks.carvedVoxels += t.carvedVoxels;
            stats.tracks.removedMass += t.removedMass;
            stats.tracks.compactedMass += t.compactedMass;
        }
    progress.report(0.3);
    progress.throwIfCancelled();

    const SprayColliders colliders{state.snow.surface.get(), scene.objects.get()};
    for (int k = 0; k < s.substeps; ++k) {
        // A lump thrown where the track left snow (thinner than a voxel, or off its edge) stays in it.
        for (const SprayParticle &p : thrown[k])
            if (outsideSnow(*state.snow.surface, p.position)) state.particles.push_back(p), ++stats.thrown;
        advanceParticles(state.particles, FlightStep{dt, s.seed, firstStep + k}, colliders, s.flight, s.lumps,
                         s.deposit, state.nextId);
        progress.report(0.3 + 0.7 * double(k + 1) / s.substeps);
        progress.throwIfCancelled();
    }
    for (const SprayParticle &p : state.particles)
        (p.state == ParticleState::Flying ? stats.flying : stats.resting) += 1;
    ++state.frame;
    return stats;
}

SnowGrids spraySnapshot(const SprayState &state, const SpraySettings &s, const SubProgress &progress) {
    RasterSettings raster;
    raster.voxelSize = s.voxelSize > 0.0 ? s.voxelSize : state.snow.surface->voxelSize()[0];
    raster.maxVoxels = s.maxVoxels;
    return rasterizeSpray(state.particles, s.lumps.density, raster, progress);
}

}  // namespace firn
