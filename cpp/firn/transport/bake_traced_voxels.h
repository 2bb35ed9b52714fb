#pragma once

// The source function of the traced voxels (bake_thin_snow.h) by Monte Carlo: gathered or light traced.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/transport/bake.h"
#include "firn/transport/bake_preset.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/transport/source_lobe.h"
#include "firn/util/progress.h"

namespace firn::bake {

// The sources a traced voxel's air neighbours carry where it is gathered and thick, or lies in a traced layer
// (FaceGathering::inLayer), on each face open to air: each face's own,
// gathered where a camera sees that face, and the voxel's own grid value, what it shows those cameras
// (addFaceSources).
struct FaceSources {
    std::array<Source, 6> source;  // by face, -x, +x, -y, +y, -z, +z
    unsigned open = 0;             // bit f: face f holds one
    unsigned lit = 0;              // bit f: face f faces a light and takes its beam (kLitFaceBeamShare)
    Source shown;                  // the voxel's grid value (its other neighbours carry its mean)
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

// At most this many tracking steps for the traced voxels (about 12 processor seconds; planGathering says why),
// and a quarter of it for transport-thin pieces light traced whole (thinVoxels).
constexpr double kMaxTracedSteps = 2e8;
constexpr double kWholePieceTracedSteps = kMaxTracedSteps / 4.0;

// How the traced voxels are gathered: paths per voxel within the budget (0: over it) and what they cost.
struct GatheringPlan {
    int paths = 0;       // per voxel; 0: none (over the budget)
    double steps = 0.0;  // what they all cost at `paths`, in tracking steps (the pilot's)
    // Per voxel the renderer draws rather than scatters (drawnByRenderer); 0: `paths`. Its paths beyond `paths` are
    // priced apart (kDrawnExtraSteps), not in `steps`.
    int drawnPaths = 0;
    // Per face of the voxels' faces (gatheredVoxelFaces): kFacePathsPerVoxelPath times the preset's paths (`paths`
    // but for a small scene's raise); per lit face kLitFacePaths times the faces' multiple of half the voxel's (their
    // ratio to the faces kept); each up to the preset's cheapTracedSamples.
    int facePaths = 0;
    int litFacePaths = 0;
    // What a small scene's traced work (kSmallSceneTracedSteps) leaves beyond the preset's paths' steps: its faces may
    // take it beyond what the voxels leave of kMaxTracedSteps (gatheredVoxelFaces).
    double smallSceneSteps = 0.0;
};
// A small scene's traced work (Preset::smallSceneTracedSteps): FINAL's and REFERENCE's traced voxels may take this
// many tracking steps in all (about 6 processor seconds) in a scene of at most kSmallSceneVoxels snow voxels, and a
// share of it inversely as the snow voxels beyond (the rest of a bake grows with them: a car's 2.7 M voxels leave
// 3.7e6, under what its 3 traced voxels take at the preset's paths, so its plan is the preset's): as many paths per
// voxel as it affords, up to kMostTracedShare times the preset's cheapTracedSamples, never fewer than the preset's
// (planGathering; DRAFT, a preview, keeps the preset's).
// Where the suite's traced error is the bake's own noise, 16 times the paths or photons read several cases lower
// (docs/bake.md, per-voxel noise); a small scene's traced voxels take well under a second at the preset's counts.
// Over seeds 0-3 (docs/benchmarks.md, spray-paths): ball_thin_forward 5.4 -> 4.4 % per block (photons 16x, the trace
// 0.13 -> 1.8 processor s), ball_rgb 6.6 -> 6.3, slab_thin_forward 7.4 -> 7.1, ball_thin 3.8 -> 3.6 %.
constexpr double kSmallSceneTracedSteps = 1e8;
constexpr double kSmallSceneVoxels = 1e5;
constexpr int kMostTracedShare = 16;
// Whether a small scene's traced work is the plan's to take, or light tracing took it (layerFaces).
enum class SmallSceneWork { Available, TakenByLightTracing };
// The paths per voxel to gather `voxels` with, their cost per path measured on a few of them first: the preset's,
// fewer within kMaxTracedSteps, more where they cost little or a small scene's traced work (where available) affords
// them. Light tracing at the gathering's cost (lightTracedAtGatheringCost) follows the plan's steps.
GatheringPlan planGathering(const Scene &scene, const Preset &preset, const std::vector<openvdb::Coord> &voxels,
                            std::uint64_t seed, SmallSceneWork smallScene = SmallSceneWork::Available);

// The voxels' sources gathered by brute force, `samples` paths each, `drawnSamples` (0: `samples`) those the renderer
// draws rather than scatters (drawnByRenderer).
MonteCarloVoxels traceSources(const Scene &scene, const std::vector<openvdb::Coord> &voxels, int samples,
                              std::uint64_t seed, const SubProgress &progress, int drawnSamples = 0);

// Which traced voxels' faces gather their own source (addFaceSources), and at what cost.
struct FaceGathering {
    int paths = 0;        // per face, where the budget holds them
    int fewestPaths = 0;  // else as many as fit, these at the least; none where even these pass the budget
    double budget = 0.0;  // tracking steps all the faces may take, priced at the faces' own (addFaceSources' pilot)
    // Per voxel: it lies in a traced layer (light traced whole), whose faces open to air on one side gather too.
    // Empty: the gathered voxels, of which the thick ones.
    std::vector<bool> inLayer;
    // Per lit face (FaceSources::lit) where more than `paths` (litFacePaths); 0: `paths` as the others.
    int litPaths = 0;
};
// The gathered voxels' faces: the plan's facePaths, else as many as fit down to a quarter of the voxel's, within what
// the gathering leaves of kMaxTracedSteps and a small scene's traced work (GatheringPlan::smallSceneSteps); their lit
// faces the plan's litFacePaths (litFacePaths).
FaceGathering gatheredVoxelFaces(const GatheringPlan &plan);

// A gathered face's paths per path of its voxel's (planGathering), up to the preset's cheapTracedSamples (DRAFT's faces
// keep their 64): the faces' noise is the cheapest of a dense spray's errors to buy (docs/benchmarks.md, dense-faces:
// spray_dense's faces at four times half the voxel's paths, 14.7 -> 13.5 % over seeds 0-3 for 3.7 processor s of
// tracing, every path four times 1.6 points for 17 s). Within kMaxTracedSteps, priced at the faces' own steps per path
// (addFaceSources), spray_dense's 438 faces take 276-304 of the 512 and its lit faces 838-866: 14.7 -> 14.0 % over
// seeds 0-7, no seed higher, the trace 5.8 -> 7.5 processor s (face-pilot; at the voxels' price 144, face-share).
// With a small scene's traced work beside (GatheringPlan::smallSceneSteps) they take all 512 (the lit faces up to
// 1024): 13.9 -> 13.3 % over seeds 0-3, every seed lower, the trace 8.8 -> 10.7 processor s, where twice the voxels'
// paths read 13.8 % for 6 s more and the faces at 1024 13.7 % (docs/benchmarks.md, spray-faces).
constexpr int kFacePathsPerVoxelPath = 2;

// A gathered lump's lit face: its lobe pair's path-noise bias along its normal, c / N at N paths (c in paths:
// bake_traced_voxels.cpp says why), the most of it kept (the suite reference's noise per block), so the paths it
// takes, and the tracking steps those beyond the faces' own may take at most (about 1.3 processor seconds on
// spray_dense's lit faces, whose 350 take 2e7).
constexpr double kLitFaceFitNoise = 7.0, kLitFaceFitBias = 0.02;
constexpr int kLitFacePaths = int(kLitFaceFitNoise / kLitFaceFitBias + 0.5);  // 350
constexpr double kLitFaceExtraSteps = 5e7;
// Paths per lit face where the faces take `paths` each and those paths cost the lit faces `litSteps` tracking steps in
// all: `wanted`, else as many beyond `paths` as kLitFaceExtraSteps affords; never fewer than `paths`.
int litFacePaths(int paths, int wanted, double litSteps);

// A traced layer's faces (`inLayer` per voxel of `voxels`, light traced whole): as many paths as gathering a voxel
// would take, within what the light tracing leaves of kMaxTracedSteps.
FaceGathering layerFaces(const Scene &scene, const Preset &preset, const std::vector<openvdb::Coord> &voxels,
                         std::vector<bool> inLayer, std::uint64_t seed);

// What addFaceSources traced: the faces' paths each (0: none), their number, and the tracking steps a face's path
// takes, measured by its pilot on a few of them (what the faces' budget is priced at).
struct FacesTraced {
    int paths = 0;
    std::size_t faces = 0;
    double stepsPerPath = 0.0;
};

// The face sources (FaceSources) of the traced `voxels` that are gathered and thick or lie in a traced layer
// (`how`), added to `traced`; none where they would cost more than its budget.
FacesTraced addFaceSources(const Scene &scene, const SnowTopology &topo, const std::vector<openvdb::Coord> &voxels,
                           const FaceGathering &how, std::uint64_t seed, const SubProgress &progress,
                           MonteCarloVoxels &traced);

// The voxels' sources light traced within `share` of `budget` tracking steps (planLightTracing); none (empty) where
// that is not affordable.
MonteCarloVoxels lightTraceSources(const Scene &scene, const std::vector<openvdb::Coord> &voxels, std::uint64_t seed,
                                   const SubProgress &progress, BakeStats &stats, double budget = kMaxTracedSteps,
                                   double share = 1.0);

// Forward scattering snow light traced at what gathering it costs; none (empty) where that does not apply.
MonteCarloVoxels lightTracedAtGatheringCost(const Scene &scene, const std::vector<openvdb::Coord> &voxels,
                                            const GatheringPlan &plan, std::uint64_t seed, const SubProgress &progress,
                                            BakeStats &stats);

}  // namespace firn::bake
