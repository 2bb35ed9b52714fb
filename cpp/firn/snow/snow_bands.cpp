#include "firn/snow/snow_bands.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <openvdb/tools/Prune.h>
#include <tbb/parallel_for.h>

#include "firn/geometry/ray_caster.h"
#include "firn/snow/snow_volume_bound.h"
#include "firn/snow/snowfall.h"
#include "firn/util/error.h"

namespace firn {

namespace {

constexpr int kMaxBands = 16;           // 2^15 x 1 cm: 330 m voxels, past any pixel
constexpr double kSurfaceMarginVoxels = 3.0;  // the level set's half-width (snow_rasterizer.cpp)

// Each band draws its own seeded sites: independent of the other bands' counts.
std::uint64_t bandSeed(std::uint64_t seed, int level) {
    return seed + std::uint64_t(level + 1) * 0x9E3779B97F4A7C15ull;
}

// Deactivates the voxels whose centres lie outside [near, far) m from `from`: density to zero, the level set to
// its background on its side.
void clipToDistances(openvdb::FloatGrid &grid, const glm::dvec3 &from, double nearDistance, double farDistance,
                     bool levelSet) {
    using Leaf = openvdb::FloatTree::LeafNodeType;
    std::vector<Leaf *> leaves;
    grid.tree().getNodes(leaves);
    const float background = grid.background();
    const openvdb::math::Transform &xform = grid.transform();
    tbb::parallel_for(std::size_t(0), leaves.size(), [&](std::size_t l) {
        for (auto it = leaves[l]->beginValueOn(); it; ++it) {
            const openvdb::Vec3d p = xform.indexToWorld(it.getCoord());
            const double d = glm::length(glm::dvec3(p.x(), p.y(), p.z()) - from);
            if (d >= nearDistance && d < farDistance) continue;
            it.setValue(levelSet ? std::copysign(background, *it) : 0.0f);
            it.setValueOff();
        }
    });
    if (levelSet) openvdb::tools::pruneLevelSet(grid.tree());
    else openvdb::tools::pruneInactive(grid.tree());
}

// The balls whose spheres reach [near, far) m from `from`, grown by `margin` m, in their original order.
std::vector<Metaball> ballsReaching(const std::vector<Metaball> &balls, const glm::dvec3 &from, double nearDistance,
                                    double farDistance, double margin) {
    std::vector<Metaball> out;
    for (const Metaball &b : balls) {
        const double d = glm::length(glm::dvec3(b.centre) - from);
        if (d + b.radius >= nearDistance - margin && d - b.radius < farDistance + margin) out.push_back(b);
    }
    return out;
}

double farthestVertex(const TriangleMesh &mesh, const glm::dvec3 &from) {
    double far = 0.0;
    for (const glm::vec3 &p : mesh.positions) far = std::max(far, glm::length(glm::dvec3(p) - from));
    return far;
}

}  // namespace

SnowBands generateSnowBands(const TriangleMesh &targets, const TriangleMesh &occluders,
                            const SnowLayerSettings &settings, const CameraFootprint &camera, Progress *progress,
                            const std::vector<float> &depthWeights) {
    settings.validate();
    camera.validate();
    if (targets.empty()) throw InvalidArgument("no target triangles to put snow on (objects without faces?)");
    if (!depthWeights.empty() && depthWeights.size() != targets.positions.size())
        throw InvalidArgument("depth weights: " + std::to_string(depthWeights.size()) + " for " +
                              std::to_string(targets.positions.size()) + " target vertices");
    if (progress) progress->report(0.0, "finding where snow lands");
    SnowBands out;
    const ShelteredTargets sheltered = shelterTargets(targets, occluders, -glm::normalize(settings.direction));
    const TriangleMesh &oriented = sheltered.oriented();
    const RayCaster &shelter = *sheltered.shelter;
    out.openSurfaces = sheltered.openSurfaces;
    const double fine = settings.effectiveVoxelSize();
    const std::vector<LodBand> bands =
        lodBands(camera, fine, settings.spacing, farthestVertex(oriented, camera.position), kMaxBands);
    const BandTargets split = splitTargetsByBand(oriented, depthWeights, camera, bands, fine);
    out.outOfView = split.outOfView;
    if (std::all_of(split.meshes.begin(), split.meshes.end(), [](const TriangleMesh &m) { return m.empty(); }))
        throw InvalidArgument("no target is in the camera's view: levels of detail keep only the snow the camera "
                              "can see (aim the scene camera at the targets, or turn levels of detail off)");

    // Sure refusals first, in milliseconds: each band's snow volume over its voxel's volume.
    RasterSettings budget = settings.raster();
    const double leastWeight = leastDepthWeight(depthWeights);
    double bound = 0.0;
    for (std::size_t k = 0; k < bands.size(); ++k) {
        if (split.meshes[k].empty()) continue;
        SnowfallSettings snowfall = settings.snowfall();
        snowfall.spacing = bands[k].spacing;
        bound += snowVoxelLowerBound(split.meshes[k], shelter, snowfall, settings.depth, bands[k].voxelSize);
    }
    checkVoxelBudget(leastWeight * bound, budget, "at least (with levels of detail)");

    // Sites, sheltering and balls: once, each band's targets at its spacing.
    std::vector<std::size_t> sitesPerBand(bands.size(), 0);
    double sites = 0.0, estimate = 0.0;
    for (std::size_t k = 0; k < bands.size(); ++k) {
        if (split.meshes[k].empty()) continue;
        const LodBand &band = bands[k];
        SnowfallSettings snowfall = settings.snowfall();
        snowfall.spacing = band.spacing;
        snowfall.seed = bandSeed(settings.seed, band.level);
        snowfall.maxSites = settings.maxVoxels - sites;
        const double begin = 0.4 * double(k) / double(bands.size());
        const auto landed = findLandingSites(split.meshes[k], shelter, snowfall,
                                             SubProgress(progress, begin, begin + 0.4 / double(bands.size())),
                                             split.weights[k]);
        MetaballLayoutSettings layout = settings.layout();
        layout.spacing = band.spacing;
        layout.seed = snowfall.seed;
        const std::vector<Metaball> balls = layoutMetaballs(landed, layout);
        out.metaballs.insert(out.metaballs.end(), balls.begin(), balls.end());
        sitesPerBand[k] = landed.size();
        sites += double(landed.size());
        // The snow's volume plus a voxel's shell above and below, 1.5x for edges (estimateVoxelCount's margin).
        const double h = band.voxelSize;
        estimate += 1.5 * double(landed.size()) * band.spacing * band.spacing * (settings.depth + 2.0 * h) / (h * h * h);
    }
    checkVoxelBudget(estimate, budget);
    requireLandedSnow(out.metaballs);

    // Each band rasterizes every ball that reaches it, at its voxel size, then keeps its own distances.
    if (progress) progress->report(0.45, "building the snow volumes");
    double used = 0.0;
    for (std::size_t k = 0; k < bands.size(); ++k) {
        const LodBand &band = bands[k];
        const double h = band.voxelSize, margin = kSurfaceMarginVoxels * h;
        const std::vector<Metaball> balls =
            ballsReaching(out.metaballs, camera.position, band.nearDistance, band.farDistance, 2.0 * margin);
        if (balls.empty()) continue;
        RasterSettings raster = budget;
        raster.voxelSize = h;
        raster.maxVoxels = settings.maxVoxels - used;
        const double begin = 0.45 + 0.55 * double(k) / double(bands.size());
        SnowBand snow{band, rasterizeSnow(balls, raster, SubProgress(progress, begin, begin + 0.5 / bands.size())),
                      sitesPerBand[k]};
        clipToDistances(*snow.grids.density, camera.position, band.nearDistance, band.farDistance, false);
        clipToDistances(*snow.grids.surface, camera.position, band.nearDistance - margin, band.farDistance + margin,
                        true);
        const double active = double(snow.grids.density->activeVoxelCount());
        if (active == 0.0) continue;
        used += active;
        out.bands.push_back(std::move(snow));
    }
    if (progress) progress->report(1.0, "done");
    return out;
}

}  // namespace firn
