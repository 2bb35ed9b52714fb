#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "firn/transport/baked_grids.h"
#include "firn/transport/scene.h"
#include "firn/util/progress.h"

namespace firn {

enum class BakeQuality {
    Draft,      // fewer sky and shadow rays and photons, looser solve: for previews
    Final,      // the diffusion solve at full accuracy
    Reference,  // surface voxels by brute-force Monte Carlo (slow; for checking and small scenes)
};

struct BakeSettings {
    BakeQuality quality = BakeQuality::Final;
    std::uint64_t seed = 0;
    // 0: the quality's default.
    int skySamples = 0;        // sky rays per boundary face
    int sunSamples = 0;        // points on a sun's disc per shadow test
    double tolerance = 0.0;    // relative residual of the diffusion solve
    int referenceSamples = 0;  // Reference: paths per direction per surface voxel
    // The source grids' voxel size in density voxels: 1 keeps them as fine as the density, 2 stores an eighth
    // of the voxels, which is what Cycles' memory follows (baked_grids.h: coarsenedSources). 0: the finest whose
    // dense box Cycles will allocate stays within kSourceBudgetBytes.
    int sourceScale = 0;
    // Light tracing (docs/bake.md Method 3) where gathering per voxel is over the budget; false leaves those voxels
    // to the diffusion (the tests and benches that measure the diffusion's lumps).
    bool lightTracing = true;
};

// What Cycles (dense volume textures, no NanoVDB) may allocate for the six source grids: 16 bytes per voxel
// of their bounding box each.
constexpr double kSourceBudgetBytes = 512.0 * 1024 * 1024;

struct BakeStats {
    std::size_t unknowns = 0, airFaces = 0, occluderFaces = 0, surfaceVoxels = 0;
    std::size_t skyTracedVoxels = 0;           // surface voxels whose sky was traced (the others' from donors)
    std::size_t tracedVoxels = 0;              // optically thin voxels lit by Monte Carlo instead of the solve
    std::size_t scatterVoxels = 0;             // density voxels where the renderer scatters (scatterMask)
    int tracedPaths = 0;                       // paths per voxel where traced from them (planGathering)
    std::size_t tracedFaces = 0;               // their faces gathered apart (addFaceSources), with
    int facePaths = 0;                         // these paths each (their lit faces' may take more)
    std::size_t lightTracedVoxels = 0;         // of which by light tracing (paths from the lights), with
    long photons = 0;                          // these photons
    std::size_t lightTracingBytes = 0;         // the sums they add to (LightTracingPlan::sumsBytes)
    int passes = 0;                            // diffusion solves per channel (1 + snow-to-snow bounces)
    int sourceScale = 1;                       // the source grids' voxel size in density voxels
    std::vector<std::array<int, 3>> iterations;  // CG iterations per pass, per colour channel
    int beamIterations = 0;                    // the beams' own solve, one channel (bake.cpp, solveBeamsApart)
    std::vector<std::array<double, 3>> relativeResidual;  // per pass, per colour channel
    // Per phase: voxels and faces, sun and sky tracing, Monte Carlo in thin snow, diffusion solves, gathering
    // between snow surfaces, writing the grids.
    struct Phases {
        double topology = 0, light = 0, trace = 0, solve = 0, gather = 0, grids = 0;
    };
    // The trace runs beside the light (bake.cpp): its wall seconds overlap the light's; its processor seconds
    // are its own thread's (its loops' chunks that other threads took count in the light's).
    Phases seconds;     // wall clock
    Phases cpuSeconds;  // processor time of all threads: what the bake cost, whatever else the machine runs
};

// Computes the light scattered inside the snow, all orders, from the scene's suns and sky, with the
// occluders' shadows, the light they reflect into the snow (once, and exactly for the surface the snow
// lies on) and the light snow surfaces send each other across the air.
//
// Method (docs/bake.md): exact attenuation of the suns' beams and the sky's light through the snow and
// past occluders; a similarity-scaled diffusion solve (D = 1 / (3 sigma_tr), sigma_tr = sigma_a +
// sigma_s (1 - g)) over the voxels, finite volumes with exponential fitting, extrapolated boundaries
// (Marshak) to air and albedo boundaries to occluders, sources placed at their true depth inside the
// (optically thick) surface voxels; multigrid-preconditioned CG per colour channel. The radiance leaving
// each surface voxel is rebuilt from its fluxes with the angular shapes of thick snow (sun lobe, escape
// function); inside, the source function follows from the fluence and its gradient. Where snow hides part
// of a surface's sky, its light is gathered from the first solution and the solve repeated.
BakedGrids bakeScattering(const Scene &scene, const BakeSettings &settings, Progress *progress = nullptr,
                          BakeStats *stats = nullptr);
// The progress's stage while the sun and sky light and the thin snow are traced side by side (fractions 0.05 to
// 0.4, half each).
inline constexpr char kLightAndTraceStage[] = "Tracing sun and sky light, and thin snow";

// The source grids of a snow with nothing to light (an empty density: a spray's frame without lumps, which
// bakeScattering refuses), without a bake: empty, with the density's transform and a bake's metadata. Throws
// InvalidArgument when the density has an active voxel.
BakedGrids emptyBakedGrids(const openvdb::FloatGrid &density, const VolumeOptics &optics, const BakeSettings &settings);

}  // namespace firn
