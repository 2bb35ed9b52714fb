#pragma once

// The few lines every Embree user in the core shares: device errors as exceptions, and a ray record.
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

}  // namespace firn
