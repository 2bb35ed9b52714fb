#pragma once

#include <cstdint>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/spray/emitter.h"
#include "firn/spray/particles.h"

namespace firn {

struct EmissionSettings {
    // Lumps thrown per m^2 of emitter per m it travels through the snow (1/m^3): a patch dA moving at speed v
    // inside the snow emits rate x v x dA lumps per second.
    double rate = 20000.0;
    double spreadAngle = 0.6;  // rad: half-angle of the cone, around straight up, of the throw
    double throwSpeed = 0.5;   // the throw's speed as a fraction of the emitter's local speed
    double cellSize = 0.02;    // m: the emitter is sampled on cells this size (inside the snow or not, per cell)

    void validate() const;
};

// The lumps an emitter throws during one sub-step, while it moves from `from` (its rectangle at the sub-step's
// start) to `to` (at its end), over `dt` s. A cell of the rectangle emits while its centre is inside the snow
// (surface level set < 0, sampled at the start) at the mean rate rate x speed x cell area, the count rounded up or
// down at random so that its expectation is exact. Each lump starts at a random point of its cell with the
// velocity of that point of the rectangle, plus a throw of throwSpeed x that speed in a direction uniform in the
// cone of spreadAngle around -down. Every random number comes from the stream of (seed, emitter, step, cell), so
// the lumps do not depend on the thread count. Ids run from nextId (which advances). Throws BudgetExceeded
// before allocating when more than `maxNew` lumps would be thrown.
SprayParticles emitLumps(const EmitterRectangle &from, const EmitterRectangle &to, double dt,
                         const openvdb::FloatGrid &surface, const glm::dvec3 &down, const EmissionSettings &emission,
                         const LumpSettings &lumps, std::uint64_t seed, std::uint64_t emitterIndex,
                         std::uint64_t stepIndex, std::uint64_t &nextId, std::size_t maxNew);

}  // namespace firn
