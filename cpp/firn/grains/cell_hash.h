#pragma once

// Grains binned by grid cell, for neighbour queries while grains arrive one at a time: an open-addressing hash
// table (linear probing, power-of-two capacity) from a cell's key to the newest entry of its list, and the lists
// threaded through one array of entries. No allocation per cell (std::unordered_map of vectors spent most of
// accumulation's time finding buckets and allocating), and a cell's grains come newest first.
#include <cstdint>
#include <vector>

#include "firn/util/random.h"

namespace firn {

class CellHash {
  public:
    // Different cells may share a key; that only adds candidates, which the callers' exact tests reject.
    static std::uint64_t key(std::int64_t i, std::int64_t j, std::int64_t k) {
        const std::uint64_t h = mix64(static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^
                                      static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4Full ^
                                      static_cast<std::uint64_t>(k) * 0x165667B19E3779F9ull);
        return h == kEmpty ? 1 : h;
    }

    void insert(std::uint64_t cellKey, unsigned grain) {
        if (2 * (used_ + 1) > slots_.size()) grow();
        Slot &slot = find(cellKey);
        if (slot.key == kEmpty) slot = Slot{cellKey, kNone}, ++used_;
        entries_.push_back(Entry{grain, slot.head});
        slot.head = static_cast<std::int32_t>(entries_.size() - 1);
    }

    // Calls visit(grain) for the grains of a cell, newest first, until visit returns false.
    template <class Visit>
    void forEach(std::uint64_t cellKey, Visit &&visit) const {
        if (slots_.empty()) return;
        for (std::int32_t e = findConst(cellKey).head; e != kNone; e = entries_[e].next)
            if (!visit(entries_[e].grain)) return;
    }

    void clear() {
        slots_.clear();
        entries_.clear();
        used_ = 0;
    }

  private:
    static constexpr std::uint64_t kEmpty = 0;
    static constexpr std::int32_t kNone = -1;
    struct Slot {
        std::uint64_t key = kEmpty;
        std::int32_t head = kNone;  // newest entry of the cell
    };
    struct Entry {
        unsigned grain;
        std::int32_t next;  // older entry of the same cell
    };

    Slot &find(std::uint64_t cellKey) { return slots_[indexOf(cellKey)]; }
    const Slot &findConst(std::uint64_t cellKey) const { return slots_[indexOf(cellKey)]; }
    std::size_t indexOf(std::uint64_t cellKey) const {
        const std::size_t mask = slots_.size() - 1;
        std::size_t i = cellKey & mask;
        while (slots_[i].key != kEmpty && slots_[i].key != cellKey) i = (i + 1) & mask;
        return i;
    }
    void grow() {
        std::vector<Slot> old = std::move(slots_);
        slots_.assign(old.empty() ? 1024 : 2 * old.size(), Slot{});
        for (const Slot &s : old)
            if (s.key != kEmpty) find(s.key) = s;
    }

    std::vector<Slot> slots_;
    std::vector<Entry> entries_;
    std::size_t used_ = 0;
};

}  // namespace firn
