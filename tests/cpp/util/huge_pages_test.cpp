// The bake's large per-voxel arrays are mapped on 2 MiB boundaries and offered to transparent huge pages
// (docs/benchmarks.md, lead-83). Whether the kernel grants them is its setting's, not asserted here.
#include "firn/util/huge_pages.h"

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <new>
#include <numeric>
#include <vector>

#include <sys/mman.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "firn/util/unwritten_vector.h"

namespace firn {

namespace {

constexpr std::uintptr_t kHugePage = std::uintptr_t(2) << 20;

bool onHugePageBoundary(const void *p) { return reinterpret_cast<std::uintptr_t>(p) % kHugePage == 0; }

}  // namespace

TEST(HugePaged, BlocksStartOnBoundariesZeroedAndAreUnmappedWhenFreed) {
    const auto page = std::uintptr_t(sysconf(_SC_PAGESIZE));
    for (const std::size_t bytes : {std::size_t(1), kHugePagedBytes, kHugePagedBytes + 12345, std::size_t(9) << 20}) {
        auto *block = static_cast<unsigned char *>(allocateHugePaged(bytes));
        EXPECT_TRUE(onHugePageBoundary(block)) << bytes;
        EXPECT_EQ(block[0], 0u);
        EXPECT_EQ(block[bytes - 1], 0u);
        std::memset(block, 0xAB, bytes);  // every byte asked for is writable
        EXPECT_EQ(block[bytes - 1], 0xAB);
        freeHugePaged(block, bytes);
        // Unmapped, from its first page to the last of the huge pages it was mapped in: mincore answers ENOMEM
        // where a page is not mapped.
        const std::uintptr_t mapped = (bytes + kHugePage - 1) / kHugePage * kHugePage;
        for (const std::uintptr_t offset : {std::uintptr_t(0), mapped - page}) {
            unsigned char resident = 0;
            errno = 0;
            EXPECT_EQ(mincore(block + offset, page, &resident), -1) << bytes << " " << offset;
            EXPECT_EQ(errno, ENOMEM) << bytes << " " << offset;
        }
    }
}

TEST(HugePaged, ASizeNoMappingCanHoldThrowsBadAlloc) {
    // Rounded up to whole huge pages without the check, it wrapped around to a small mapping.
    EXPECT_THROW(allocateHugePaged(std::size_t(-1) - 100), std::bad_alloc);
}

TEST(HugePaged, UnwrittenVectorsKeepTheirValuesAcrossTheThreshold) {
    // Grown one element at a time from a few bytes past kHugePagedBytes: each reallocation moves the values from a
    // malloc'd block to a mapped one, or between mapped ones.
    UnwrittenVector<std::uint64_t> v;
    const std::size_t n = 3 * kHugePagedBytes / sizeof(std::uint64_t) + 17;
    for (std::size_t i = 0; i < n; ++i) v.push_back(i * 2654435761u);
    EXPECT_TRUE(onHugePageBoundary(v.data()));
    bool kept = true;
    for (std::size_t i = 0; i < n; ++i) kept = kept && v[i] == i * 2654435761u;
    EXPECT_TRUE(kept);
    const UnwrittenVector<std::uint64_t> copy(v);
    EXPECT_TRUE(onHugePageBoundary(copy.data()));
    EXPECT_EQ(copy, v);
    v.resize(100), v.shrink_to_fit();  // back below the threshold: malloc's again
    EXPECT_EQ(v.size(), 100u);
    EXPECT_EQ(v[99], std::uint64_t(99) * 2654435761u);
}

}  // namespace firn
