#pragma once

#include <algorithm>
#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/huge_pages.h"

namespace firn {

// An allocator whose vectors grow (resize) without writing their new elements: for per-unknown arrays that a
// parallel loop then writes in full. Each page is first touched (faulted in and cleared by the kernel) by the thread
// that writes it, not zero-filled on the calling thread beforehand; copies and assign(n, value) write as usual.
// (docs/benchmarks.md, car-prof: such fills made 14-36 % of the solve stages' processor time single-threaded.)
// Large blocks are huge-paged (huge_pages.h).
template <class T>
struct UnwrittenAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = UnwrittenAllocator<U>;
    };
    UnwrittenAllocator() = default;
    template <class U>
    UnwrittenAllocator(const UnwrittenAllocator<U> &) noexcept {}

    T *allocate(std::size_t n) {
        if (n < kHugePagedBytes / sizeof(T)) return std::allocator<T>::allocate(n);
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        return static_cast<T *>(allocateHugePaged(n * sizeof(T)));
    }
    void deallocate(T *p, std::size_t n) noexcept {
        if (n < kHugePagedBytes / sizeof(T)) return std::allocator<T>::deallocate(p, n);
        freeHugePaged(p, n * sizeof(T));
    }

    template <class U>
    void construct(U *) noexcept {
        static_assert(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>,
                      "an element left unwritten must be plain data");
    }
    template <class U, class... Args>
    void construct(U *p, Args &&...args) {
        ::new (static_cast<void *>(p)) U(std::forward<Args>(args)...);
    }
};

template <class T, class U>
bool operator==(const UnwrittenAllocator<T> &, const UnwrittenAllocator<U> &) {
    return true;
}
template <class T, class U>
bool operator!=(const UnwrittenAllocator<T> &, const UnwrittenAllocator<U> &) {
    return false;
}

// A vector whose resize leaves its new elements to be written (UnwrittenAllocator).
template <class T>
using UnwrittenVector = std::vector<T, UnwrittenAllocator<T>>;

// v made n copies of `value`, written in parallel: each page is first touched by the thread that writes it (what
// assign(n, value) does on the calling thread alone).
template <class T>
void parallelAssign(UnwrittenVector<T> &v, std::size_t n, const T &value) {
    v.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384), [&](const tbb::blocked_range<std::size_t> &r) {
        std::fill(v.begin() + r.begin(), v.begin() + r.end(), value);
    });
}

// `to` made a copy of `from`, written in parallel (what `to = from` does on the calling thread alone).
template <class T>
void parallelCopy(const UnwrittenVector<T> &from, UnwrittenVector<T> &to) {
    to.resize(from.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, from.size(), 16384),
                      [&](const tbb::blocked_range<std::size_t> &r) {
                          std::copy(from.begin() + r.begin(), from.begin() + r.end(), to.begin() + r.begin());
                      });
}

}  // namespace firn
