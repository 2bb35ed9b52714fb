#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "firn/geometry/ray_caster.h"
#include "firn/snow/snow_rasterizer.h"
#include "firn/spray/emission.h"
#include "firn/spray/emitter.h"
#include "firn/spray/flight.h"
#include "firn/spray/particles.h"
#include "firn/spray/tracks.h"
#include "firn/util/progress.h"

namespace firn {

// Everything a spray simulation asks for. Lengths in m, times in s, densities in kg/m^3.
struct SpraySettings {
    EmissionSettings emission;
    LumpSettings lumps;
    FlightSettings flight;
    TrackSettings tracks;
    int substeps = 4;            // sub-steps per frame (1..1000)
    bool deposit = true;         // lumps that come to rest stay (drawn where they lie); false: they vanish
    bool cutTracks = true;       // emitters cut tracks in the snow
    double voxelSize = 0.0;      // m of the spray's grids; 0: the snow's
    double maxParticles = 2e6;   // lumps the simulation may hold, counted as the balls they could split into
    double maxVoxels = 50e6;     // voxels of the spray's grids, and of one frame's track (its swept volume)
    std::uint64_t seed = 0;

    // Throws InvalidArgument naming the first setting out of range.
    void validate() const;
};

// What moves: the emitters' rectangles at every frame of the sequence, and the objects lumps land on.
struct SprayScene {
    std::vector<Emitter> emitters;
    std::shared_ptr<const RayCaster> objects;  // may be null
    double fps = 24.0;                         // frames per second

    std::size_t frameCount() const { return emitters.empty() ? 0 : emitters.front().frames.size(); }
    // Throws InvalidArgument unless there is an emitter, every emitter has a rectangle for each of at least two
    // frames, and fps is positive.
    void validate() const;
};

// A simulation between two frames: all it needs to go on. Random numbers are counter-based (util/random.h, keyed by
// the seed, the sub-step's number and a particle's id), so (frame, nextId, particles, snow) is the whole state.
struct SprayState {
    std::size_t frame = 0;    // index of the last frame simulated: the emitters' rectangles at this frame
    std::uint64_t nextId = 0;  // id of the next lump thrown or split off
    SprayParticles particles;
    SnowGrids snow;           // the snow with the tracks cut so far
};

struct SprayFrameStats {
    std::size_t thrown = 0;    // lumps thrown this frame (not counting those that started inside the snow)
    std::size_t flying = 0;    // lumps in the air at the frame's end
    std::size_t resting = 0;   // lumps at rest at the frame's end
    TrackStats tracks;         // tracks.carvedVoxels > 0: the snow's grids changed
};

// The state at the first frame: no lumps, the snow as it is (taken, not copied).
SprayState initialSprayState(SnowGrids snow);

// Simulates from frame state.frame to state.frame + 1, in settings.substeps sub-steps of 1 / (fps substeps) s: each
// emitter throws lumps where it is inside the snow (as the snow was at the frame's start), cuts its track over the
// frame (so the lumps start in the groove it leaves), then the lumps fly, land and split. Deterministic for a seed
// whatever the thread count. Throws BudgetExceeded over settings.maxParticles.
SprayFrameStats simulateSprayFrame(SprayState &state, const SprayScene &scene, const SpraySettings &settings,
                                   const SubProgress &progress);

// The spray's grids at the state's frame (spray/spray_density.h at settings.voxelSize, or the snow's).
SnowGrids spraySnapshot(const SprayState &state, const SpraySettings &settings, const SubProgress &progress);

}  // namespace firn
