// Per-unknown arrays are sized without writing (UnwrittenVector) and then filled by parallel loops, so that each page
// is first touched by the thread that writes it (docs/benchmarks.md, car-prof and lead-80).
#include "firn/util/unwritten_vector.h"

#include <algorithm>
#include <cstdint>

#include <gtest/gtest.h>

namespace firn {

TEST(UnwrittenVector, ParallelAssignWritesEveryElementWhetherTheVectorShrinksOrGrows) {
    UnwrittenVector<std::int32_t> v;
    parallelAssign(v, 300000, std::int32_t(7));
    ASSERT_EQ(v.size(), 300000u);
    EXPECT_TRUE(std::all_of(v.begin(), v.end(), [](std::int32_t x) { return x == 7; }));
    // Sizes off the loop's grain: a missed tail or head would keep the old 7s or hold whatever the pages held.
    parallelAssign(v, 250001, std::int32_t(3));
    ASSERT_EQ(v.size(), 250001u);
    EXPECT_TRUE(std::all_of(v.begin(), v.end(), [](std::int32_t x) { return x == 3; }));
    parallelAssign(v, 1000003, std::int32_t(-1));
    ASSERT_EQ(v.size(), 1000003u);
    EXPECT_TRUE(std::all_of(v.begin(), v.end(), [](std::int32_t x) { return x == -1; }));
    parallelAssign(v, 0, std::int32_t(5));
    EXPECT_TRUE(v.empty());
}

}  // namespace firn
