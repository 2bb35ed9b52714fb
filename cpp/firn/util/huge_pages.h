#pragma once

#include <cstddef>

namespace firn {

// Blocks of at least this many bytes are mapped apart, on 2 MiB boundaries, and their whole 2 MiB pages offered to
// the kernel's transparent huge pages (madvise MADV_HUGEPAGE, what Debian's default "madvise" mode waits for): the
// bake's per-voxel arrays are faulted in up to 512 times less often, and on a virtual machine each fault's trap costs
// more than clearing its page (docs/benchmarks.md, lead-83: the car's solve stage 2.4 processor s less). Freed blocks
// go back to the system at once, as glibc's mapped ones do.
inline constexpr std::size_t kHugePagedBytes = std::size_t(4) << 20;

// `bytes` (> 0) starting on a 2 MiB boundary, zeroed; throws std::bad_alloc where the system has no room for them.
void *allocateHugePaged(std::size_t bytes);
// Frees what allocateHugePaged(bytes) returned, given the same `bytes`.
void freeHugePaged(void *block, std::size_t bytes) noexcept;

}  // namespace firn
