#include "firn/transport/scene.h"

#include <algorithm>
#include <cmath>
#include <string>

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
    anyClosed_ = std::find(closed_.begin(), closed_.end(), 1) != closed_.end();
    caster_ = std::make_shared<RayCaster>(mesh_);
}

void validate(const Scene &scene) {
    if (!scene.medium) throw InvalidArgument("the scene has no snow medium");
    if (!scene.occluders) throw InvalidArgument("the scene's occluders are missing");
    for (const SunLight &sun : scene.suns) validate(sun);
    for (const Lamp &lamp : scene.lamps) validate(lamp);
    validate(scene.sky);
}

}  // namespace firn
