#pragma once

#include <cstdint>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/geometry/ray_caster.h"
#include "firn/spray/particles.h"

namespace firn {

struct FlightSettings {
    glm::dvec3 down{0.0, 0.0, -1.0};  // unit vector: the way gravity pulls
    double gravity = 9.81;            // m/s^2, standard gravity
    double airDensity = 1.2;          // kg/m^3, dry air at sea level and 20 C
    double dragCoefficient = 0.47;    // a sphere at Reynolds numbers 1e3-2e5 (Hoerner 1965, Fluid-Dynamic Drag)

    void validate() const;
};

// Quadratic drag F = 1/2 rho_air C_d A v^2 on a sphere of radius r (m) and density rho (kg/m^3) decelerates it by
// k v^2, k = 1/2 rho_air C_d pi r^2 / (rho 4/3 pi r^3) = 3 rho_air C_d / (8 rho r)  (1/m).
double dragPerSpeedSquared(double radius, double lumpDensity, const FlightSettings &settings);

// The speed (m/s) at which drag balances gravity: sqrt(g / k) = sqrt(2 m g / (rho_air C_d A)).
double terminalSpeed(double radius, double lumpDensity, const FlightSettings &settings);

// One step of flight, no collisions: x' = v, v' = g - k |v| v, by Strang splitting into two flows each solved
// exactly: drag alone keeps the direction and slows the speed s as s0 / (1 + k s0 t), covering ln(1 + k s0 t) / k
// (m); gravity alone adds g t to the velocity. Drag for dt/2, gravity for dt, drag for dt/2: with k = 0 this is
// x + v dt + g dt^2 / 2, v + g dt, the exact ballistic step at any dt; with drag it is second order and stable at
// any dt (each drag flow only slows, never reverses, the velocity).
void flightStep(glm::dvec3 &position, glm::dvec3 &velocity, double dt, const glm::dvec3 &gravityAcceleration,
                double dragK);

// What stops a particle. Either may be null.
struct SprayColliders {
    const openvdb::FloatGrid *snowSurface = nullptr;  // level set (m), negative inside the snow
    const RayCaster *objects = nullptr;               // triangles, world m
};

struct FlightStep {
    double dt = 0.0;            // s
    std::uint64_t seed = 0;
    std::uint64_t index = 0;    // the sub-step's number since the simulation began: its random streams
};

// Advances every flying particle by one sub-step, in parallel and deterministically whatever the thread count.
// A particle whose path (the chord of the step) crosses into the snow (surface level set < 0) or meets a triangle
// stops there, on the outside, and rests (OnSnow, OnObject); a resting particle is removed when `deposit` is
// false. A particle resting on snow that is no longer under it (the level set above two voxels, after a track cut
// it away) flies again. Flying lumps split at settings.breakRate; the new halves are appended in particle order
// with ids nextId, nextId + 1... (nextId advances).
void advanceParticles(SprayParticles &particles, const FlightStep &step, const SprayColliders &colliders,
                      const FlightSettings &flight, const LumpSettings &lumps, bool deposit, std::uint64_t &nextId);

}  // namespace firn
