#include "firn/transport/skin_ring.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/incident_light.h"
#include "firn/util/work_check.h"

namespace firn::bake {

namespace {

// Voxels from a node out to patchSurface, the staircase's half voxel: the patches' beams are read just outside it
// (IncidentLight::Beam::atSurface), after the snow in front, so the sun they miss is the skin beyond it.
constexpr double kPatchSurfaceOffset = 0.5;

}  // namespace

bool spreadsAsSphere(const SnowTopology &topo, const openvdb::Coord &carrier,
                     openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, double kappaPerVoxel) {
    if (!(kappaPerVoxel > 0.0)) return false;
    for (int k = 0; k < 27; ++k) {
        const std::int32_t j = index.getValue(carrier + blockOffset(k));
        if (j >= 0 && topo.patches[std::size_t(j)].sharp) return false;
    }
    return index.getValue(carrier) >= 0;
}

double carriedSunSpread(double kappaPerVoxel, double d) {
    return std::pow(1.0 + kappaPerVoxel * d, smallBall(kappaPerVoxel) ? -kSmallBallSpread : -2.0);
}

double surfaceOffset(const Medium &medium, const openvdb::Coord &node, const glm::dvec3 &n,
                     Medium::Accessor &density) {
    const glm::dvec3 centre = medium.voxelCentre(node);
    const double h = medium.voxelSize();
    const double half = 0.5 * std::max(medium.densityAt(centre, density), medium.densityAt(centre - h * n, density));
    // Outward in sixteenths of a voxel to the first point under half, linear between the last two.
    constexpr double kFrom = -1.0, kTo = 1.5, kStep = 1.0 / 16.0;
    double before = medium.densityAt(centre + kFrom * h * n, density);
    for (double t = kFrom + kStep; t <= kTo + 1e-9; t += kStep) {
        const double rho = medium.densityAt(centre + t * h * n, density);
        if (rho < half && before >= half) return t - kStep * (half - rho) / (before - rho);
        before = rho;
    }
    return 0.5;
}

double skinRingGrowth(const Medium &medium, const SnowTopology &topo, std::size_t i, double kappaPerVoxel,
                      double offset, Medium::Accessor &density) {
    // The profile: optical depth per voxel at heights y = (k + 1/2) dy above the patch's surface, out to 3 voxels
    // (the ramp and its trilinear reach end within two).
    constexpr int kSteps = 24;
    constexpr double dy = 3.0 / kSteps;  // voxels
    const double h = medium.voxelSize();
    const glm::dvec3 n = topo.patches[i].normal, surface = medium.voxelCentre(topo.coord[i]) + offset * h * n;
    std::array<double, kSteps> depth{};
    int clear = 0;  // the profile, linear between the samples, is exactly 0 from sample `clear` on (the air above)
    for (int k = 0; k < kSteps; ++k) {
        depth[k] = medium.optics().extinctionPerDensity * medium.densityAt(surface + (k + 0.5) * dy * h * n, density) * h;
        if (depth[k] != 0.0) clear = k + 1;
    }
    clear = std::min(clear, kSteps - 1);
    const double R = 1.0 / kappaPerVoxel, top = R + kSteps * dy;
    double ring = 0.0;  // (1 + kappa delta)^2 - 1
    // Heights grow along each chord and from chord to chord, so the marches stop where the depth is 0 for good:
    // the terms they skip add exactly 0 (the sums are the full midpoint rules', bit for bit).
    for (int m = 0; m < kSteps; ++m) {
        const double b = R + (m + 0.5) * dy;  // the ray's nearest distance from the centre, voxels
        if ((b - R) / dy - 0.5 >= clear) break;
        const double reach = std::sqrt(top * top - b * b);
        const int steps = int(std::ceil(reach / dy));
        double tau = 0.0;  // both halves of the chord, midpoint rule along it
        for (int u = 0; u < steps; ++u) {
            const double along = (u + 0.5) * reach / steps;
            const double at = (std::sqrt(along * along + b * b) - R) / dy - 0.5;  // in samples
            if (at >= clear) break;
            // Linear between the samples, the nearest below the first.
            const int k = int(at);
            tau += 2.0 * (at <= 0.0 ? depth[0] : depth[k] + (at - k) * (depth[k + 1] - depth[k])) * reach / steps;
        }
        ring += 2.0 * kappaPerVoxel * kappaPerVoxel * b * (1.0 - std::exp(-tau)) * dy;
    }
    return 1.0 + ring;
}

double skinRingIrradiance(double growth, double mu0, double sunIrradiance) {
    const double sinAlpha = std::sqrt(std::max(0.0, 1.0 - 1.0 / growth));
    if (!(mu0 > 0.0) || mu0 >= sinAlpha) return 0.0;
    return (growth - 1.0) * sunIrradiance / (4.0 * sinAlpha);
}

SurfaceValues<float> skinRingGrowths(const Scene &scene, const SnowTopology &topo, const SubProgress &progress) {
    SurfaceValues<float> growth(topo.surfaceSlot, topo.surfaceVoxels(), 1.0f);
    if (scene.suns.empty()) return growth;
    const Medium &medium = *scene.medium;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        Medium::Accessor density = medium.accessor();
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        WorkCheck work(progress);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const SurfacePatch &patch = topo.patches[i];
            if (!patch.isSurface() || patch.sharp) continue;
            work.add(WorkCheck::kVoxel);
            const double kappa = surfaceCurvature(topo, topo.coord[i], index);
            const double widest = (1.0 + 3.0 * kappa) * (1.0 + 3.0 * kappa);
            const glm::dvec3 surface = patchSurface(medium, topo, i);
            bool grazed = false;
            for (std::size_t s = 0; s < scene.suns.size() && !grazed; ++s) {
                const double mu0 = glm::dot(patch.normal, towardsBeam(scene, s, surface));
                grazed = mu0 > 0.0 && mu0 * mu0 < 1.0 - 1.0 / widest;
            }
            if (grazed && !smallBall(kappa) && spreadsAsSphere(topo, topo.coord[i], index, kappa))
                growth.surface(i) = float(skinRingGrowth(medium, topo, i, kappa, kPatchSurfaceOffset, density));
        }
    });
    return growth;
}

}  // namespace firn::bake
