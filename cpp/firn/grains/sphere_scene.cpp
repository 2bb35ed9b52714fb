#include "firn/grains/sphere_scene.h"

#include <algorithm>
#include <cmath>

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>

#include "firn/geometry/embree.h"

namespace firn {

struct SphereScene::Impl {
    EmbreeScene embree;
};

std::optional<double> raySphereEntry(const glm::dvec3 &origin, const glm::dvec3 &direction, const glm::dvec3 &centre,
                                     double radius) {
    // |o + t d - c|^2 = r^2 with |d| = 1: t = -b -+ sqrt(b^2 - c), b = (o - c).d, c = |o - c|^2 - r^2.
    const glm::dvec3 oc = origin - centre;
    const double b = glm::dot(oc, direction);
    const double c = glm::dot(oc, oc) - radius * radius;
    if (c <= 0.0) return std::nullopt;  // origin inside or on the sphere: no entry ahead
    const double discriminant = b * b - c;
    if (discriminant < 0.0 || b >= 0.0) return std::nullopt;
    // The numerically stable root: c / (-b + sqrt(disc)) equals -b - sqrt(disc) without cancellation.
    return c / (-b + std::sqrt(discriminant));
}

SphereScene::SphereScene(const GrainSet &grains, std::size_t count)
    : impl_(std::make_unique<Impl>()), grains_(grains), count_(std::min(count, grains.size())) {
    if (count_ > 0) {
        RTCGeometry geometry = rtcNewGeometry(impl_->embree.device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        auto *points = static_cast<float *>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                    RTC_FORMAT_FLOAT4, 4 * sizeof(float), count_));
        throwOnEmbreeError(impl_->embree.device, "allocate the grains (out of memory?)");
        for (std::size_t i = 0; i < count_; ++i) {
            const glm::dvec3 &c = grains.centres[i];
            // Slightly larger in float, so rounding never loses a grain Embree should report; the exact test follows.
            const float r = static_cast<float>(grains.radii[i]) * (1.0f + 1e-5f);
            points[4 * i + 0] = static_cast<float>(c.x);
            points[4 * i + 1] = static_cast<float>(c.y);
            points[4 * i + 2] = static_cast<float>(c.z);
            points[4 * i + 3] = r;
        }
        impl_->embree.attach(geometry);
    }
    impl_->embree.commit("build the grain scene");
}

SphereScene::~SphereScene() = default;

std::optional<SphereScene::Hit> SphereScene::intersect(const glm::dvec3 &origin, const glm::dvec3 &direction,
                                                       double tFar, long ignoreGrain) const {
    if (count_ == 0) return std::nullopt;
    const glm::vec3 o(origin), d(direction);
    float tNear = 0.0f;
    const float tFarFloat = std::isfinite(tFar) ? static_cast<float>(tFar) * (1.0f + 1e-6f) + 1e-9f
                                                : std::numeric_limits<float>::infinity();
    // Each pass skips one grain Embree reports but the exact test rejects (the one being left, a float miss):
    // a handful of passes at most; the bound only guards against a pathological pile-up.
    for (int pass = 0; pass < 64; ++pass) {
        const RTCRayHit query = intersectEmbree(impl_->embree.scene, o, d, tNear, tFarFloat);
        if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
        const unsigned grain = query.hit.primID;
        if (static_cast<long>(grain) != ignoreGrain) {
            const glm::dvec3 &centre = grains_.centres[grain];
            if (const auto t = raySphereEntry(origin, direction, centre, grains_.radii[grain])) {
                if (*t > tFar) return std::nullopt;
                return Hit{*t, grain, glm::normalize(origin + *t * direction - centre)};
            }
        }
        tNear = std::nextafter(query.ray.tfar, std::numeric_limits<float>::infinity());
    }
    return std::nullopt;
}

}  // namespace firn
