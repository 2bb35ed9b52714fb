#include "firn/geometry/ray_caster.h"

#include <string>

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>

#include "firn/util/error.h"

namespace firn {

struct RayCaster::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<glm::vec3> normals;  // unit, per triangle
};

namespace {

void throwOnDeviceError(RTCDevice device, const char *what) {
    const RTCError error = rtcGetDeviceError(device);
    if (error != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("Embree failed to ") + what + " (error " + std::to_string(error) + ")");
}

RTCRay makeRay(const glm::vec3 &o, const glm::vec3 &d, float tNear, float tFar) {
    RTCRay ray{};
    ray.org_x = o.x, ray.org_y = o.y, ray.org_z = o.z;
    ray.dir_x = d.x, ray.dir_y = d.y, ray.dir_z = d.z;
    ray.tnear = tNear;
    ray.tfar = tFar;
    ray.mask = 0xFFFFFFFF;
    ray.flags = 0;
    return ray;
}

}  // namespace

RayCaster::RayCaster(const TriangleMesh &mesh) : impl_(std::make_unique<Impl>()), empty_(mesh.empty()) {
    impl_->device = rtcNewDevice(nullptr);
    if (!impl_->device) throw std::runtime_error("Embree could not create a device");
    impl_->scene = rtcNewScene(impl_->device);
    // Few rays per triangle here: a fast build (Morton) beats a better tree.
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_LOW);
    if (!empty_) {
        RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto *vertices = static_cast<float *>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
        auto *indices = static_cast<unsigned *>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
        throwOnDeviceError(impl_->device, "allocate the scene (out of memory?)");
        for (std::size_t i = 0; i < mesh.positions.size(); ++i)
            for (int k = 0; k < 3; ++k) vertices[3 * i + k] = mesh.positions[i][k];
        impl_->normals.resize(mesh.triangles.size());
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            for (int k = 0; k < 3; ++k) indices[3 * t + k] = mesh.triangles[t][k];
            impl_->normals[t] = glm::normalize(mesh.crossNormal(t));
        }
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(impl_->scene, geometry);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(impl_->scene);
    throwOnDeviceError(impl_->device, "build the scene");
}

RayCaster::~RayCaster() {
    if (impl_->scene) rtcReleaseScene(impl_->scene);
    if (impl_->device) rtcReleaseDevice(impl_->device);
}

bool RayCaster::occluded(const glm::vec3 &origin, const glm::vec3 &direction, float tNear, float tFar) const {
    if (empty_) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = makeRay(origin, direction, tNear, tFar);
    rtcOccluded1(impl_->scene, &context, &ray);
    return ray.tfar < 0.0f;  // Embree marks a blocked ray with tfar = -inf
}

std::optional<RayCaster::Hit> RayCaster::intersect(const glm::vec3 &origin, const glm::vec3 &direction,
                                                   float tNear, float tFar) const {
    if (empty_) return std::nullopt;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit query{};
    query.ray = makeRay(origin, direction, tNear, tFar);
    query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &context, &query);
    if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    return Hit{query.ray.tfar, query.hit.primID, impl_->normals[query.hit.primID]};
}

}  // namespace firn
