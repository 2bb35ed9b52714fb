#pragma once

#include <cmath>
#include <cstddef>

namespace firn {

// Dense symmetric positive definite systems A x = b by Cholesky (A = L L^T), A n x n in row-major order: the
// traced voxels' fit by direction (5 x 5, traced_source.cpp) and the multigrid's coarsest level (multigrid.cpp).

// Factors A in place: its lower triangle becomes L (the upper one is neither read nor written). False where a
// pivot is not above `minPivot` (A singular, or not positive definite): A is then left half factored.
inline bool choleskyFactor(double *A, std::size_t n, double minPivot = 0.0) {
    for (std::size_t j = 0; j < n; ++j) {
        double d = A[j * n + j];
        for (std::size_t k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
        if (!(d > minPivot)) return false;
        A[j * n + j] = std::sqrt(d);
        for (std::size_t i = j + 1; i < n; ++i) {
            double s = A[i * n + j];
            for (std::size_t k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
            A[i * n + j] = s / A[j * n + j];
        }
    }
    return true;
}

// Solves L L^T x = b in place (b becomes x), L the lower triangle choleskyFactor left.
inline void choleskySolve(const double *L, std::size_t n, double *b) {
    for (std::size_t i = 0; i < n; ++i) {  // L y = b
        double s = b[i];
        for (std::size_t k = 0; k < i; ++k) s -= L[i * n + k] * b[k];
        b[i] = s / L[i * n + i];
    }
    for (std::size_t i = n; i-- > 0;) {  // L^T x = y
        double s = b[i];
        for (std::size_t k = i + 1; k < n; ++k) s -= L[k * n + i] * b[k];
        b[i] = s / L[i * n + i];
    }
}

// Both: b becomes x; false (b unchanged) where choleskyFactor fails.
inline bool solveSymmetric(double *A, std::size_t n, double *b, double minPivot = 0.0) {
    if (!choleskyFactor(A, n, minPivot)) return false;
    choleskySolve(A, n, b);
    return true;
}

}  // namespace firn
