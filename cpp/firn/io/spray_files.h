#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "firn/geometry/mesh.h"
#include "firn/spray/sequence.h"
#include "firn/util/progress.h"

namespace firn {

// The files of a spray sequence (docs/spray.md), each frame's in `directory`, #### its Blender frame number:
//   spray_####.vdb    the lumps' `density` and `surface` grids (a snow layer's contract)
//   snow_####.vdb     the snow with its tracks, written only at frames where the tracks changed it
//   spray_####.state  the simulation's state after the frame, written last: the frame's completion marker
struct SprayFramePaths {
    std::string spray, snow, state;
};
SprayFramePaths sprayFramePaths(const std::string &directory, int frame);

// A state file: what resuming needs besides the snow, which lies in the snow file of `snowFrame` (or the input's
// when there is none yet), and the fingerprint of the inputs that made it.
struct SavedSprayState {
    std::uint64_t fingerprint = 0;
    std::size_t frame = 0;              // index of the frame in the sequence (0: its first frame)
    std::uint64_t nextId = 0;
    std::optional<int> snowFrame;       // Blender frame of the latest snow file; none: the input snow
    SprayParticles particles;
};

// Writes atomically (temporary file, then rename). Throws WriteError.
void writeSprayState(const std::string &path, const SavedSprayState &state);
// Throws ReadError for a missing, truncated or foreign file. StateRead::Header reads all but the particles (their
// count is still checked against the file's length): what finding the frame to resume from needs.
enum class StateRead { Whole, Header };
SavedSprayState readSprayState(const std::string &path, StateRead what = StateRead::Whole);

// A whole simulation, as the bindings hand it over.
struct SprayJob {
    std::string snowPath;        // VDB with the snow's `density` and `surface`
    std::vector<Emitter> emitters;
    TriangleMesh objects;        // lumps land on these (may be empty)
    double fps = 24.0;
    int firstFrame = 1;          // Blender frame number of the emitters' first rectangles
    SpraySettings settings;
    std::string directory;       // where the frames' files go
};

struct SprayRun {
    std::optional<int> resumedAfter;  // the last frame found complete from an earlier run of the same job
    std::vector<int> framesWritten;   // frames simulated and written by this run
    std::vector<int> snowFrames;      // frames of the whole sequence that have a snow file
    SprayFrameStats last;             // the last frame's statistics (zero when nothing was left to do)
    // Wall-clock seconds this run spent, summed over its frames (for benchmarks; nothing depends on them).
    double simulateSeconds = 0.0, rasterizeSeconds = 0.0, writeSeconds = 0.0;
};

// Simulates the frames in order and writes each one's files; the state file of a frame is written after its VDB
// files, so a run that was interrupted (cancelled, killed) resumes after the last complete frame whose state was
// made by the same inputs (settings, objects, fps, first frame, the snow file's bytes, and the emitters up to that
// frame: a sequence made longer resumes too) and ends with the same files as a run that was never interrupted. Reports to `progress` (may be null) and stops when it is
// cancelled. Throws InvalidArgument, BudgetExceeded, ReadError, WriteError, Cancelled.
SprayRun runSpraySequence(const SprayJob &job, Progress *progress);

}  // namespace firn
