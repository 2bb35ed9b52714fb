#pragma once

#include <cstdint>

#include "firn/util/progress.h"

namespace firn {

// Checks a Progress for cancellation at bounded work, not at bounded iterations: a loop adds its work in units of
// about a tracking step's (some tens of nanoseconds; a voxel of a bake's per-voxel loops counts kVoxel) and every
// kUnits of them throwIfCancelled runs, so Esc stops a bake within a fraction of a second however large the scene.
// One per loop body: a TBB chunk has its own (the auto partitioner hands a thread chunks of a large share of the
// scene, so a check per chunk is not bounded), and it checks when made, so that no chunk starts after a cancel.
// A SubProgress of no Progress never throws.
class WorkCheck {
  public:
    static constexpr std::uint64_t kUnits = std::uint64_t(1) << 16;
    static constexpr std::uint64_t kVoxel = 256;  // a voxel's light, a source or a grid value: a check per 256

    explicit WorkCheck(const SubProgress &progress) : progress_(progress) { progress_.throwIfCancelled(); }

    // `units` more done: a check when they bring the count to kUnits (the count then starts again).
    void add(std::uint64_t units = 1) {
        units_ += units;
        if (units_ >= kUnits) units_ = 0, progress_.throwIfCancelled();
    }

  private:
    SubProgress progress_;  // a copy: callers may pass a temporary
    std::uint64_t units_ = 0;
};

}  // namespace firn
