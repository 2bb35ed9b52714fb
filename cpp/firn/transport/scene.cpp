#include "firn/transport/scene.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/common.hpp>
#include <glm/vector_relational.hpp>

#include "firn/geometry/orientation.h"
#include "firn/util/error.h"

namespace firn {

Occluders::Occluders(TriangleMesh mesh, std::vector<Rgb> albedo)
    : mesh_(std::move(mesh)), albedo_(std::move(albedo)) {
    if (albedo_.size() != mesh_.triangleCount())
        throw InvalidArgument("occluders need one albedo per triangle: " + std::to_string(albedo_.size()) +
                              " for " + std::to_string(mesh_.triangleCount()) + " triangles");
    for (const Rgb &a : albedo_)
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(a[c]) || a[c] < 0.0 || a[c] > 1.0)
                throw InvalidArgument("occluder albedo must lie in [0, 1] per channel");
    closed_ = inClosedSurface(mesh_);
    for (std::size_t t = 0; t < mesh_.triangleCount(); ++t) {
        if (!closed_[t]) continue;
        for (int k = 0; k < 3; ++k) {
            closedMin_ = glm::min(closedMin_, glm::dvec3(mesh_.vertex(t, k)));
            closedMax_ = glm::max(closedMax_, glm::dvec3(mesh_.vertex(t, k)));
        }
    }
    caster_ = std::make_shared<RayCaster>(mesh_, RayCaster::Rays::Many);  // every patch casts its sky rays at them
}

bool Occluders::mayEnclose(const glm::vec3 &p) const {
    const glm::dvec3 at(p);
    return glm::all(glm::greaterThanEqual(at, closedMin_)) && glm::all(glm::lessThanEqual(at, closedMax_));
}

std::vector<unsigned> Occluders::closedIn(const glm::dvec3 &lo, const glm::dvec3 &hi) const {
    if (glm::any(glm::greaterThan(lo, closedMax_)) || glm::any(glm::lessThan(hi, closedMin_))) return {};
    std::vector<unsigned> in = caster_->trianglesInBox(lo, hi);
    in.erase(std::remove_if(in.begin(), in.end(), [&](unsigned t) { return !closed_[t]; }), in.end());
    return in;
}

void validate(const Scene &scene) {
    if (!scene.medium) throw InvalidArgument("the scene has no snow medium");
    if (!scene.occluders) throw InvalidArgument("the scene's occluders are missing");
    for (const SunLight &sun : scene.suns) validate(sun);
    for (const Lamp &lamp : scene.lamps) validate(lamp);
    validate(scene.sky);
}

}  // namespace firn
