#pragma once

#include <cstdint>
#include <cstring>

namespace firn {

// Counter-based random numbers: the value depends only on (seed, stream, index), never on thread
// scheduling, so parallel loops stay deterministic. SplitMix64 finalizer (Steele et al. 2014).
inline std::uint64_t mix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

// A stream number from a point's coordinates (their bits), chained onto `stream`: what is drawn for a point (or a
// triangle, chaining its corners) then depends on where it is, not on its index, so inputs given in another order
// give the same draws. Each step (h ^ word) x odd constant is a bijection of h, so points that differ give
// different numbers; Rng's constructor mixes them (a million triangles' streams: a few ms, not three mix64 each).
inline std::uint64_t pointStream(float x, float y, float z, std::uint64_t stream = 0) {
    std::uint32_t bits[3];
    const float coordinates[3] = {x, y, z};
    std::memcpy(bits, coordinates, sizeof bits);
    stream = (stream ^ (std::uint64_t(bits[0]) << 32 | bits[1])) * 0x9E3779B97F4A7C15ull;
    return (stream ^ bits[2]) * 0xD6E8FEB86659FD93ull;
}

class Rng {
  public:
    Rng(std::uint64_t seed, std::uint64_t stream) : state_(mix64(seed ^ mix64(stream + 0x632BE59BD9B4E019ull))) {}

    std::uint64_t nextBits() { return mix64(state_++); }
    // Uniform in [0, 1).
    double uniform() { return static_cast<double>(nextBits() >> 11) * 0x1.0p-53; }

  private:
    std::uint64_t state_;
};

}  // namespace firn
