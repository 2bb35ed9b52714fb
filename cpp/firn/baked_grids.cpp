#include "firn/baked_grids.h"

#include <algorithm>
#include <cmath>

#include <openvdb/tools/Interpolation.h>

#include "firn/error.h"

namespace firn {

openvdb::GridPtrVec BakedGrids::grids() const { return {source[0], source[1], source[2], source[3]}; }

BakedGrids BakedGrids::find(const openvdb::GridPtrVec &grids) {
    BakedGrids out;
    for (std::size_t i = 0; i < kNames.size(); ++i) {
        for (const auto &grid : grids)
            if (grid->getName() == kNames[i]) out.source[i] = openvdb::gridPtrCast<openvdb::Vec3fGrid>(grid);
        if (!out.source[i]) throw InvalidArgument(std::string("no Vec3f grid named ") + kNames[i]);
    }
    return out;
}

Rgb renderBaked(const Scene &scene, const BakedGrids &baked, const Ray &ray) {
    const Medium &medium = *scene.medium;
    double t0, t1;
    if (!medium.clipToBounds(ray.origin, ray.direction, t0, t1)) return Rgb(0.0);
    if (const auto hit = scene.occluders->caster().intersect(glm::vec3(ray.origin), glm::vec3(ray.direction)))
        t1 = std::min(t1, double(hit->distance));
    const double h = medium.voxelSize(), k = medium.optics().extinctionPerDensity;
    const double dt = h / 32.0;  // fine enough for the steepest ramp of one voxel to be integrated exactly
    Medium::Accessor density = medium.accessor();
    std::array<openvdb::Vec3fGrid::ConstAccessor, 4> source{
        baked.source[0]->getConstAccessor(), baked.source[1]->getConstAccessor(),
        baked.source[2]->getConstAccessor(), baked.source[3]->getConstAccessor()};
    const glm::dvec3 w = -ray.direction;  // towards the viewer
    Rgb radiance(0.0);
    double transmittance = 1.0;
    for (double t = t0; t < t1 && transmittance > 1e-6; t += dt) {
        const glm::dvec3 p = ray.origin + (t + 0.5 * dt) * ray.direction;
        const double sigmaT = k * medium.densityAt(p, density);
        if (sigmaT <= 0.0) continue;
        const glm::dvec3 ijk = medium.worldToIndex(p);
        const openvdb::Vec3d xyz(ijk.x, ijk.y, ijk.z);
        openvdb::Vec3f S = openvdb::tools::BoxSampler::sample(source[0], xyz);
        for (int a = 0; a < 3; ++a) S += float(w[a]) * openvdb::tools::BoxSampler::sample(source[1 + a], xyz);
        const double opacity = 1.0 - std::exp(-sigmaT * dt);
        radiance += transmittance * opacity * Rgb(S.x(), S.y(), S.z());
        transmittance *= 1.0 - opacity;
    }
    return radiance;
}

}  // namespace firn
