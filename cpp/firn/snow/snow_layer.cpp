#include "firn/snow/snow_layer.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "firn/snow/snow_volume_bound.h"
#include "firn/util/error.h"
#include "firn/util/threads.h"

namespace firn {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kIceDensity = 917.0;  // kg/m^3

void require(bool ok, const char *setting, const char *range, double value) {
    if (ok) return;
    std::ostringstream msg;
    msg << setting << " must be " << range << " (got " << value << ")";
    throw InvalidArgument(msg.str());
}

}  // namespace

void SnowLayerSettings::validate() const {
    require(depth > 0.0 && depth <= 20.0, "depth", "between 0 and 20 m", depth);
    require(spacing > 0.0 && spacing <= 10.0, "spacing", "between 0 and 10 m", spacing);
    require(spacing >= depth / 200.0, "spacing", "at least depth / 200 (a finer spacing only costs time)", spacing);
    require(maxSlope > 0.0 && maxSlope <= kPi / 2.0, "maximum slope", "between 0 and 90 degrees (in radians)",
            maxSlope);
    require(spread >= 0.0 && spread < kPi / 2.0, "spread", "between 0 and 90 degrees (in radians)", spread);
    require(randomness >= 0.0 && randomness <= 1.0, "randomness", "between 0 and 1", randomness);
    require(smoothness >= 0.0 && smoothness <= 1.0, "smoothness", "between 0 and 1", smoothness);
    require(compaction >= 0.0 && compaction <= 1.0, "compaction", "between 0 and 1", compaction);
    require(densityTop > 0.0 && densityTop <= kIceDensity, "top density", "between 0 and 917 kg/m^3 (ice)",
            densityTop);
    require(densityBottom > 0.0 && densityBottom <= kIceDensity, "bottom density",
            "between 0 and 917 kg/m^3 (ice)", densityBottom);
    require(exposureRays >= 1 && exposureRays <= 1024, "exposure rays", "between 1 and 1024", exposureRays);
    require(voxelSize >= 0.0 && voxelSize <= depth, "voxel size", "0 (automatic) or at most the depth",
            voxelSize);
    require(maxVoxels >= 1.0 && maxVoxels <= kMaxVoxelBudget, "voxel budget", "between 1 and 1e11", maxVoxels);
    const float len = glm::length(direction);
    require(std::isfinite(len) && len > 1e-6f, "snowfall direction length", "non-zero", len);
    require(glm::dot(direction, glm::vec3(0, 0, -1)) / len > 0.0f, "snowfall direction", "pointing downwards (z < 0)",
            direction.z);
}

double SnowLayerSettings::effectiveVoxelSize() const {
    if (voxelSize > 0.0) return voxelSize;
    // 10 voxels through the full depth, and at least 2.5 across a ball's radius so balls don't alias.
    return std::min(depth / 10.0, metaballRadius(layout()) / 2.5);
}

SnowfallSettings SnowLayerSettings::snowfall() const {
    SnowfallSettings s;
    s.direction = glm::normalize(direction);
    s.spread = spread;
    s.maxSlope = maxSlope;
    s.spacing = spacing;
    s.exposureRays = exposureRays;
    s.seed = seed;
    s.maxSites = maxVoxels;  // a site that gets snow costs at least a voxel
    return s;
}

MetaballLayoutSettings SnowLayerSettings::layout() const {
    return {depth, spacing, smoothness, randomness, seed};
}

RasterSettings SnowLayerSettings::raster() const {
    RasterSettings r;
    r.voxelSize = effectiveVoxelSize();
    r.maxVoxels = maxVoxels;
    r.compaction = {densityTop, densityBottom, compaction, depth};
    return r;
}

SnowLayer generateSnowLayer(const TriangleMesh &targets, const TriangleMesh &occluders,
                            const SnowLayerSettings &settings, Progress *progress,
                            const std::vector<float> &depthWeights) {
    settings.validate();
    if (targets.empty()) throw InvalidArgument("no target triangles to put snow on (objects without faces?)");
    SnowLayer layer;
    layer.voxelSize = settings.effectiveVoxelSize();
    if (progress) progress->report(0.0, "finding where snow lands");

    const ShelteredTargets sheltered = shelterTargets(targets, occluders, -glm::normalize(settings.direction));
    const TriangleMesh &oriented = sheltered.oriented();
    const RayCaster &shelter = *sheltered.shelter;
    layer.openSurfaces = sheltered.openSurfaces;
    // Sure refusals first: placing and sheltering sites grows with the area (minutes on a large plane).
    checkVoxelBudget(leastDepthWeight(depthWeights) * snowVoxelLowerBound(oriented, shelter, settings.snowfall(), settings.depth,
                                                       layer.voxelSize),
                     settings.raster(), "at least");
    const auto sites = findLandingSites(oriented, shelter, settings.snowfall(), SubProgress(progress, 0.0, 0.4),
                                        depthWeights);
    layer.siteCount = sites.size();
    layer.metaballs = layoutMetaballs(sites, settings.layout());
    const RasterSettings raster = settings.raster();
    const double estimate = estimateVoxelCount(layer.metaballs, settings.spacing, raster.voxelSize);
    checkVoxelBudget(estimate, raster);
    requireLandedSnow(layer.metaballs);
    if (progress) progress->report(0.45, "building the snow volume");
    layer.grids = rasterizeSnow(layer.metaballs, raster, SubProgress(progress, 0.45, 1.0));
    if (progress) progress->report(1.0, "done");
    return layer;
}

ShelteredTargets shelterTargets(const TriangleMesh &targets, const TriangleMesh &occluders, const glm::vec3 &up) {
    ShelteredTargets out;
    out.targets = &targets;
    OpenSurfaceTurns turns;
    // Without occluders the shelter is built on the targets themselves (they outlive it): no joined copy.
    runBeside([&] { turns = findOpenSurfaceTurns(targets, up); },
              [&] {
                  out.shelter = occluders.empty() ? RayCaster::over(targets)
                                                  : std::make_unique<const RayCaster>(merge({&targets, &occluders}));
              });
    out.openSurfaces = turns.changed;
    if (out.openSurfaces.triangles > 0) {
        out.turned = targets;
        applyTurns(out.turned, turns);
        out.shelter = std::make_unique<const RayCaster>(merge({&out.turned, &occluders}));
    }
    return out;
}

double leastDepthWeight(const std::vector<float> &depthWeights) {
    if (depthWeights.empty()) return 1.0;
    const float least = *std::min_element(depthWeights.begin(), depthWeights.end());
    return least >= 0.0f && least <= 1.0f ? least : 1.0;
}

void requireLandedSnow(const std::vector<Metaball> &balls) {
    if (balls.empty()) throw InvalidArgument(
        "no snow lands on the targets: every surface is sheltered, steeper than the maximum slope or the underside "
        "of a closed object (if a closed object's normals point inward, recalculate them: Mesh > Normals > "
        "Recalculate Outside)");
}

double meanInteriorDensity(const SnowGrids &grids) {
    using Leaf = openvdb::FloatTree::LeafNodeType;
    std::vector<const Leaf *> leaves;
    grids.density->tree().getNodes(leaves);
    const double h = grids.density->voxelSize()[0];
    struct Sum {
        double mass = 0.0, count = 0.0;
    };
    const Sum total = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, leaves.size()), Sum{},
        [&](const tbb::blocked_range<std::size_t> &r, Sum sum) {
            for (std::size_t l = r.begin(); l != r.end(); ++l) {
                const Leaf *sdf = grids.surface->tree().probeConstLeaf(leaves[l]->origin());
                for (auto it = leaves[l]->cbeginValueOn(); it; ++it)
                    if (sdf && sdf->getValue(it.pos()) <= -0.5 * h) sum.mass += *it, sum.count += 1.0;
            }
            return sum;
        },
        [](Sum a, const Sum &b) { return Sum{a.mass + b.mass, a.count + b.count}; });
    return total.count > 0.0 ? total.mass / total.count : 0.0;
}

}  // namespace firn
