#pragma once

// The few lines every Embree user in the core shares: device errors as exceptions, a device with its one scene,
// and a ray record.
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>
#include <glm/vec3.hpp>

namespace firn {

inline void throwOnEmbreeError(RTCDevice device, const char *what) {
    const RTCError error = rtcGetDeviceError(device);
    if (error != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("Embree failed to ") + what + " (error " + std::to_string(error) + ")");
}

// An Embree device and its one scene, released together. Geometries are attached built; commit() builds the BVH.
class EmbreeScene {
  public:
    EmbreeScene() {
        device = rtcNewDevice(nullptr);
        if (!device) throw std::runtime_error("Embree could not create a device");
        scene = rtcNewScene(device);
    }
    ~EmbreeScene() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
    EmbreeScene(const EmbreeScene &) = delete;
    EmbreeScene &operator=(const EmbreeScene &) = delete;

    // Commits a filled geometry into the scene; the scene keeps the only reference.
    void attach(RTCGeometry geometry) {
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(scene, geometry);
        rtcReleaseGeometry(geometry);
    }
    void commit(const char *what) {
        rtcCommitScene(scene);
        throwOnEmbreeError(device, what);
    }

    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
};

// origin + t * direction, t in [tNear, tFar] (m when direction is unit).
inline RTCRay makeEmbreeRay(const glm::vec3 &o, const glm::vec3 &d, float tNear, float tFar) {
    RTCRay ray{};
    ray.org_x = o.x, ray.org_y = o.y, ray.org_z = o.z;
    ray.dir_x = d.x, ray.dir_y = d.y, ray.dir_z = d.z;
    ray.tnear = tNear;
    ray.tfar = tFar;
    ray.mask = 0xFFFFFFFF;
    ray.flags = 0;
    return ray;
}

// The nearest hit on origin + t * direction, t in [tNear, tFar]: query.hit.geomID is RTC_INVALID_GEOMETRY_ID
// for none, else query.ray.tfar is the distance and query.hit.primID the primitive.
inline RTCRayHit intersectEmbree(RTCScene scene, const glm::vec3 &origin, const glm::vec3 &direction, float tNear,
                                 float tFar) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit query{};
    query.ray = makeEmbreeRay(origin, direction, tNear, tFar);
    query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &query);
    return query;
}

}  // namespace firn
