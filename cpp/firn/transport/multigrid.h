#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <openvdb/openvdb.h>

#include "firn/transport/voxel_links.h"
#include "firn/util/progress.h"
#include "firn/util/unwritten_vector.h"

namespace firn {

// A symmetric positive-definite 7-point operator on voxels: the finite-volume form of
//   -div(D grad phi) + sigma_a phi = source
// with row i reading  diag_i x_i - sum_k conductance_ik x_neighbour(i,k)  (conductance >= 0, diag >= sum).
template <typename T>
struct Stencil {
    // Per row, its neighbours (voxel_links.h): the topology's own table, so that conjugate gradients read its links
    // rather than a copy of them (24 bytes per row; the multigrid's finest level holds its rows regrouped by colour,
    // with a table of its own).
    using Neighbours = VoxelLinks;
    using Voxels = UnwrittenVector<openvdb::Coord>;
    static constexpr std::int32_t kNone = -1;
    // Voxel per row (axis neighbours differ by 1); shared, so that the bake's finest level reads the topology's
    // voxels rather than a copy of them (12 bytes per row, copied for every solve).
    std::shared_ptr<const Voxels> coord;
    std::shared_ptr<const Neighbours> neighbour;
    // Sized unwritten (UnwrittenVector): whoever sizes them writes every row, in parallel.
    UnwrittenVector<std::array<T, 6>> conductance;
    UnwrittenVector<T> diag;

    std::size_t size() const { return diag.size(); }
    T row(std::size_t i, const T *x) const;  // (A x)_i
    void apply(const T *x, T *y) const;      // y = A x, parallel
};
using StencilOperator = Stencil<double>;

// A row's remainder: diag minus the conductances to its neighbours, summed in double. The solver keeps it apart
// (in float), so the operator's nearly cancelling row sums are not left to a float diagonal's rounding.
inline double rowRemainder(double diag, const std::array<double, 6> &conductance,
                           const std::array<std::int32_t, 6> &neighbour) {
    double rest = diag;
    for (int k = 0; k < 6; ++k)
        if (neighbour[k] >= 0) rest -= conductance[k];
    return rest;
}

// Solves A x = b by conjugate gradients (OpenVDB's pcg, in the caller's b and x) preconditioned with one
// symmetric V-cycle of aggregation multigrid: 2x2x2 voxel blocks per coarser level, coarse operators summed from the fine one
// (conductances halved, as rediscretizing at twice the spacing would give), red-black Gauss-Seidel
// smoothing (each level's rows regrouped by colour, so that a colour's sweep streams its own rows alone; the finest
// level's coefficients regrouped in the caller's storage, in place), a dense Cholesky solve at the bottom. The V-cycle works in single precision (it only has to
// precondition; the iteration itself is double), halving its memory traffic. Work per iteration is linear in the voxel count and
// the iteration count does not grow with the domain.
class MultigridSolver {
  public:
    // The vectors conjugate gradients work in, for a caller that solves systems of one size in turn: kept
    // between solves, their pages are reused rather than mapped and cleared afresh (the bake's three channels).
    // A spent solver's levels (release) serve the next solver of the same rows and neighbours: their blocks,
    // neighbours and colours depend on the voxels alone, so only its operators are regrouped and summed again.
    struct Hierarchy;  // levels, defined in multigrid.cpp (so held by shared_ptr: complete where it is deleted)
    struct Workspace {
        UnwrittenVector<double> p, z;  // written before they are read
        UnwrittenVector<double> spare;      // b's storage after a solve (holding its last residual)
        std::shared_ptr<Hierarchy> levels;  // a spent solver's levels, or none
    };

    explicit MultigridSolver(StencilOperator fine);
    // The same from the operator already in single precision and its remainder (diag minus the conductances,
    // summed in double): what the solver keeps of it (the bake assembles them so, without a double copy).
    // With a workspace holding a spent solver's levels for the same rows and neighbours (release), their layout is
    // taken over: the same solver as a fresh build, bit for bit.
    MultigridSolver(Stencil<float> fine, UnwrittenVector<float> remainder, Workspace *workspace = nullptr);
    ~MultigridSolver();
    // Not copied: copies would share the levels' mutable vectors, and one's release would empty the other.
    MultigridSolver(const MultigridSolver &) = delete;
    MultigridSolver &operator=(const MultigridSolver &) = delete;

    struct Result {
        int iterations = 0;
        double relativeResidual = 0.0;  // max |b - A x| / max |b|
    };
    // The smallest relative residual asked of a solve: double precision stalls near 1e-15, and iterating on
    // rounding noise ends in 0/0 (NaN everywhere). Smaller tolerances are raised to it.
    static constexpr double kFinestTolerance = 1e-12;

    // x holds the initial guess on entry and is iterated in place; b is taken (pass it with std::move where it
    // is not needed after) and holds the residual meanwhile. Throws Cancelled when progress is cancelled (x then
    // holds the last iterate).
    Result solve(UnwrittenVector<double> b, UnwrittenVector<double> &x, double relativeTolerance, int maxIterations,
                 const SubProgress &progress, Workspace *workspace = nullptr) const;

    // The finest level's operator and remainder handed back, the solver spent: their storage can hold the next
    // system of the same size (the conductances and diagonal come back regrouped: the caller writes every row);
    // given a workspace, the levels go to it for the next solver of the same rows.
    std::pair<Stencil<float>, UnwrittenVector<float>> release(Workspace *workspace = nullptr) &&;

    int levelCount() const;

  private:
    Result iterate(UnwrittenVector<double> &b, UnwrittenVector<double> &x, double relativeTolerance, int maxIterations,
                   const SubProgress &progress, Workspace &workspace) const;

    std::shared_ptr<Hierarchy> hierarchy_;
};

}  // namespace firn
