#include "firn/util/ceil_count.h"

#include <limits>

#include <gtest/gtest.h>

namespace firn {

// A count from a length: ceil within [1, most]; a length of 1e30 steps (a spray emitter moved 1e30 m) is `most`
// without passing through an int that overflows, and NaN is 1.
TEST(CeilCount, IsTheCeilingClampedBeforeItBecomesAnInt) {
    EXPECT_EQ(ceilCount(3.2, 256), 4);
    EXPECT_EQ(ceilCount(4.0, 256), 4);
    EXPECT_EQ(ceilCount(0.3, 256), 1);
    EXPECT_EQ(ceilCount(-1e30, 256), 1);
    EXPECT_EQ(ceilCount(255.5, 256), 256);
    EXPECT_EQ(ceilCount(1e30, 256), 256);
    EXPECT_EQ(ceilCount(std::numeric_limits<double>::infinity(), 64), 64);
    EXPECT_EQ(ceilCount(std::numeric_limits<double>::quiet_NaN(), 64), 1);
}

}  // namespace firn
