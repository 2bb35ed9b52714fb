#include "firn/transport/baked_grids.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <openvdb/tools/Interpolation.h>

#include "firn/util/error.h"

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

BakedRadiance::BakedRadiance(const Scene &scene, const BakedGrids &baked)
    : scene_(scene),
      marcher_(*scene.medium),
      density_(scene.medium->accessor()),
      source_{Reader(baked.source[0]->tree()), Reader(baked.source[1]->tree()), Reader(baked.source[2]->tree()),
              Reader(baked.source[3]->tree())} {}

Rgb BakedRadiance::along(const Ray &ray, double tMax, double step) {
    const double k = scene_.medium->optics().extinctionPerDensity;
    const glm::dvec3 w = -ray.direction;  // towards the viewer
    Rgb radiance(0.0);
    double transmittance = 1.0;
    marcher_.march(ray.origin, ray.direction, tMax, step, [&](const openvdb::Vec3d &ijk, double dt) {
        const double sigmaT = k * openvdb::tools::BoxSampler::sample(density_, ijk);
        if (sigmaT <= 0.0) return true;
        openvdb::Vec3f S = openvdb::tools::BoxSampler::sample(source_[0], ijk);
        for (int a = 0; a < 3; ++a) S += float(w[a]) * openvdb::tools::BoxSampler::sample(source_[1 + a], ijk);
        const double opacity = 1.0 - std::exp(-sigmaT * dt);
        radiance += transmittance * opacity * Rgb(S.x(), S.y(), S.z());
        transmittance *= 1.0 - opacity;
        return transmittance > 1e-6;
    });
    return radiance;
}

Rgb renderBaked(const Scene &scene, const BakedGrids &baked, const Ray &ray) {
    double tMax = std::numeric_limits<double>::infinity();
    if (const auto hit = scene.occluders->caster().intersect(glm::vec3(ray.origin), glm::vec3(ray.direction)))
        tMax = hit->distance;
    // Steps of 1/32 voxel resolve the steepest density ramp (one voxel) to well under 1 %.
    return BakedRadiance(scene, baked).along(ray, tMax, 1.0 / 32.0);
}

}  // namespace firn
