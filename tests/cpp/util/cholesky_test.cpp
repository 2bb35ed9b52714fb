#include "firn/util/cholesky.h"

#include <array>
#include <limits>

#include <gtest/gtest.h>

namespace firn {

// A = L L^T with L = [2 0 0; 1 3 0; -1 2 4] (integers: every step exact in double), x = (1, -2, 3), b = A x. The
// upper triangle is never read: NaN there changes nothing.
TEST(Cholesky, SolvesAKnownSymmetricPositiveDefiniteSystem) {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    std::array<double, 9> A = {4, nan, nan,  //
                               2, 10, nan,   //
                               -2, 5, 21};
    std::array<double, 3> b = {-6, -3, 51};
    ASSERT_TRUE(solveSymmetric(A.data(), 3, b.data()));
    EXPECT_EQ(A[3], 1.0);
    EXPECT_EQ(A[6], -1.0);
    EXPECT_EQ(A[7], 2.0);
    EXPECT_EQ(A[8], 4.0);
    EXPECT_EQ(b, (std::array<double, 3>{1, -2, 3}));
}

// One factor, several right-hand sides (the multigrid's coarsest level, solved once per V-cycle).
TEST(Cholesky, FactorOnceSolveMany) {
    std::array<double, 4> A = {4, 0, 2, 10};  // L = [2 0; 1 3]
    ASSERT_TRUE(choleskyFactor(A.data(), 2));
    std::array<double, 2> b = {4, 2}, c = {6, 12};  // x = (1, 0), (1, 1)
    choleskySolve(A.data(), 2, b.data());
    choleskySolve(A.data(), 2, c.data());
    EXPECT_EQ(b, (std::array<double, 2>{1, 0}));
    EXPECT_EQ(c, (std::array<double, 2>{1, 1}));
}

// Singular ([1 2; 2 4]: the second pivot 4 - 2^2 = 0) and not positive definite ([1 2; 2 1]: -3) are reported,
// and b is left as it was; a pivot under `minPivot` too.
TEST(Cholesky, ReportsSingularAndIndefiniteSystems) {
    std::array<double, 4> singular = {1, 2, 2, 4}, indefinite = {1, 2, 2, 1}, tiny = {1, 0, 0, 1e-13};
    std::array<double, 2> b = {1, 1};
    EXPECT_FALSE(solveSymmetric(singular.data(), 2, b.data()));
    EXPECT_FALSE(solveSymmetric(indefinite.data(), 2, b.data()));
    EXPECT_EQ(b, (std::array<double, 2>{1, 1}));
    EXPECT_FALSE(choleskyFactor(tiny.data(), 2, 1e-12));
    tiny = {1, 0, 0, 1e-13};
    EXPECT_TRUE(choleskyFactor(tiny.data(), 2));
}

}  // namespace firn
