#include "firn/transport/multigrid.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "firn/util/error.h"

namespace firn {

namespace {

// -laplace(phi) + m phi = b on a ball of radius r voxels, with Robin (conductance 0.5) boundaries and a
// conductance jump of 100 across x = 0: the shape of the bake's systems.
StencilOperator ballProblem(int r, double mass) {
    StencilOperator A;
    openvdb::Int32Tree index(-1);
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> access(index);
    auto coord = std::make_shared<StencilOperator::Voxels>();
    for (int i = -r; i <= r; ++i)
        for (int j = -r; j <= r; ++j)
            for (int k = -r; k <= r; ++k)
                if (i * i + j * j + k * k <= r * r) {
                    access.setValue(openvdb::Coord(i, j, k), int(coord->size()));
                    coord->emplace_back(i, j, k);
                }
    A.coord = coord;
    const std::size_t n = coord->size();
    auto neighbour = std::make_shared<StencilOperator::Neighbours>(n);
    A.conductance.resize(n), A.diag.assign(n, mass);
    const openvdb::Coord step[6] = {openvdb::Coord(-1, 0, 0), openvdb::Coord(1, 0, 0), openvdb::Coord(0, -1, 0),
                                    openvdb::Coord(0, 1, 0),  openvdb::Coord(0, 0, -1), openvdb::Coord(0, 0, 1)};
    for (std::size_t i = 0; i < n; ++i)
        for (int f = 0; f < 6; ++f) {
            const int j = access.getValue((*coord)[i] + step[f]);
            (*neighbour)[i][f] = j;  // -1 (kNone) outside the ball
            const double c = j < 0 ? 0.5 : ((*coord)[i].x() > 0 && (*coord)[j].x() > 0 ? 100.0 : 1.0);
            A.conductance[i][f] = j < 0 ? 0.0 : c;
            A.diag[i] += c;
        }
    A.neighbour = std::move(neighbour);
    return A;
}

}  // namespace

// The operator is held in single precision (conductances, and the absorption apart from them), so the
// double-precision residual reaches about 1e-7 of the matrix's own scale.
TEST(Multigrid, SolvesToToleranceInFewIterationsAtAnySize) {
    for (int r : {8, 16, 24}) {
        StencilOperator A = ballProblem(r, 1e-3);
        const StencilOperator copy = A;
        UnwrittenVector<double> b(A.size()), x(A.size(), 0.0), Ax(A.size());
        for (std::size_t i = 0; i < b.size(); ++i) b[i] = (*A.coord)[i].z() > r / 2 ? 1.0 : 0.0;
        const MultigridSolver solver(std::move(A));
        const auto result = solver.solve(b, x, 1e-7, 100, SubProgress(nullptr, 0, 1));
        copy.apply(x.data(), Ax.data());
        double worst = 0.0;
        for (std::size_t i = 0; i < b.size(); ++i) worst = std::max(worst, std::abs(Ax[i] - b[i]));
        EXPECT_LT(worst, 1e-6);
        EXPECT_LE(result.iterations, 20) << "radius " << r;  // does not grow with the domain
        EXPECT_GE(solver.levelCount(), 2);
    }
}

// Two plates one voxel apart (z in [0, 1] and z = 3): their 2x2x2 blocks touch (z blocks 0 and 1) though no voxel
// of one links to the other, so the coarse levels must not couple them either. Lit from one plate only, the other
// stays exactly dark, and the lit one solves to tolerance.
TEST(Multigrid, BlocksThatTouchWithoutLinksStayApart) {
    constexpr int side = 24;
    auto coord = std::make_shared<StencilOperator::Voxels>();
    openvdb::Int32Tree index(-1);
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> access(index);
    for (int z : {0, 1, 3})
        for (int x = 0; x < side; ++x)
            for (int y = 0; y < side; ++y) access.setValue(openvdb::Coord(x, y, z), int(coord->size())), coord->emplace_back(x, y, z);
    const std::size_t n = coord->size();
    StencilOperator A;
    auto neighbour = std::make_shared<StencilOperator::Neighbours>(n);
    A.conductance.resize(n), A.diag.assign(n, 1e-3);
    const openvdb::Coord step[6] = {openvdb::Coord(-1, 0, 0), openvdb::Coord(1, 0, 0), openvdb::Coord(0, -1, 0),
                                    openvdb::Coord(0, 1, 0),  openvdb::Coord(0, 0, -1), openvdb::Coord(0, 0, 1)};
    for (std::size_t i = 0; i < n; ++i)
        for (int f = 0; f < 6; ++f) {
            const int j = access.getValue((*coord)[i] + step[f]);
            (*neighbour)[i][f] = j;
            A.conductance[i][f] = j < 0 ? 0.0 : 1.0;
            A.diag[i] += j < 0 ? 0.5 : 1.0;  // Robin boundaries: conductance 0.5 to the outside
        }
    A.coord = coord, A.neighbour = std::move(neighbour);
    const StencilOperator copy = A;
    UnwrittenVector<double> b(n), x(n, 0.0), Ax(n);
    for (std::size_t i = 0; i < n; ++i) b[i] = (*coord)[i].z() == 0 ? 1.0 : 0.0;
    const MultigridSolver solver(std::move(A));
    ASSERT_GE(solver.levelCount(), 2);
    const auto result = solver.solve(b, x, 1e-9, 100, SubProgress(nullptr, 0, 1));
    EXPECT_LE(result.relativeResidual, 1e-9);
    copy.apply(x.data(), Ax.data());
    for (std::size_t i = 0; i < n; ++i) {
        if ((*coord)[i].z() == 3) {
            ASSERT_EQ(x[i], 0.0) << "voxel " << i;
        }
        EXPECT_NEAR(Ax[i], b[i], 1e-6);
    }
}

// Two systems on the same voxels (a ball's, two absorptions), a right-hand side, and the second solved by a fresh
// solver in fresh vectors.
struct TwoSystems {
    StencilOperator first = ballProblem(12, 1e-2), second = onVoxelsOf(first, ballProblem(12, 1e-4));
    std::size_t n = second.size();
    UnwrittenVector<double> b = rightHandSide(second), fresh = UnwrittenVector<double>(n, 0.0);
    MultigridSolver freshSolver{second};
    MultigridSolver::Result freshResult = freshSolver.solve(b, fresh, 1e-9, 100, SubProgress(nullptr, 0, 1));

    // `A` reading `voxels`' own voxel and neighbour tables, as the bake's channels read the topology's.
    static StencilOperator onVoxelsOf(const StencilOperator &voxels, StencilOperator A) {
        A.coord = voxels.coord, A.neighbour = voxels.neighbour;
        return A;
    }
    static UnwrittenVector<double> rightHandSide(const StencilOperator &A) {
        UnwrittenVector<double> b(A.size());
        for (std::size_t i = 0; i < A.size(); ++i) b[i] = (*A.coord)[i].z() > 4 ? 1.0 : 0.0;
        return b;
    }
    // The first solved in `workspace` and spent (its levels to the workspace when `keepLevels`), the second
    // written over its operator's storage, as the bake's assembly does.
    std::pair<Stencil<float>, UnwrittenVector<float>> secondInFirstsStorage(MultigridSolver::Workspace &workspace,
                                                                         bool keepLevels) const {
        UnwrittenVector<double> x(n, 0.0);
        MultigridSolver solver(first);
        solver.solve(b, x, 1e-9, 100, SubProgress(nullptr, 0, 1), &workspace);
        auto [A, remainder] = std::move(solver).release(keepLevels ? &workspace : nullptr);
        for (std::size_t i = 0; i < n; ++i) {
            for (int k = 0; k < 6; ++k) A.conductance[i][k] = float(second.conductance[i][k]);
            A.diag[i] = float(second.diag[i]);
            remainder[i] = float(rowRemainder(second.diag[i], second.conductance[i], (*second.neighbour)[i]));
        }
        A.coord = second.coord, A.neighbour = second.neighbour;
        return {std::move(A), std::move(remainder)};
    }
    // The second's solver built with the first's spent levels in `workspace`; `copied`: over a copy of the
    // neighbour table (the same rows, another table).
    MultigridSolver secondAfterFirst(MultigridSolver::Workspace &workspace, bool copied) const {
        auto [A, remainder] = secondInFirstsStorage(workspace, true);
        if (copied) A.neighbour = std::make_shared<const StencilOperator::Neighbours>(*A.neighbour);
        return MultigridSolver(std::move(A), std::move(remainder), &workspace);
    }
};

// The bake solves a pass's three channels in the same vectors (release(), Workspace): a solve in the vectors an
// earlier solve of another system left behind takes the same iterates, bit for bit, as one in fresh vectors.
TEST(Multigrid, SolvesInAnEarlierSolvesVectorsAsInFreshOnes) {
    const TwoSystems systems;
    MultigridSolver::Workspace workspace;
    auto [A, remainder] = systems.secondInFirstsStorage(workspace, false);
    ASSERT_EQ(A.size(), systems.n);
    ASSERT_EQ(remainder.size(), systems.n);
    ASSERT_EQ(workspace.spare.size(), systems.n);
    EXPECT_EQ(workspace.levels, nullptr);
    UnwrittenVector<double> reusedB = std::move(workspace.spare);
    std::copy(systems.b.begin(), systems.b.end(), reusedB.begin());
    UnwrittenVector<double> reused(systems.n, 0.0);
    const auto reusedResult = MultigridSolver(std::move(A), std::move(remainder))
                                  .solve(std::move(reusedB), reused, 1e-9, 100, SubProgress(nullptr, 0, 1), &workspace);
    EXPECT_EQ(reusedResult.iterations, systems.freshResult.iterations);
    EXPECT_EQ(reused, systems.fresh);
}

// The bake's next channel takes over a spent solver's levels (release into the workspace): the same rows and
// neighbours, another operator. Its coarse operators summed again over the kept blocks give the iterates of a fresh
// build bit for bit, and the levels are those a fresh build makes. Levels built over another neighbour table (the
// same rows, copied) are left: their colours and blocks belong to that table.
TEST(Multigrid, TakesOverASpentSolversLevelsAsAFreshBuild) {
    const TwoSystems systems;
    MultigridSolver::Workspace elsewhere;
    EXPECT_EQ(systems.secondAfterFirst(elsewhere, true).levelCount(), systems.freshSolver.levelCount());
    EXPECT_NE(elsewhere.levels, nullptr);  // left where they were: the solver built its own
    MultigridSolver::Workspace workspace;
    const MultigridSolver taken = systems.secondAfterFirst(workspace, false);
    EXPECT_EQ(workspace.levels, nullptr);  // taken over, not copied
    EXPECT_EQ(taken.levelCount(), systems.freshSolver.levelCount());
    UnwrittenVector<double> reused(systems.n, 0.0);
    const auto takenResult = taken.solve(systems.b, reused, 1e-9, 100, SubProgress(nullptr, 0, 1), &workspace);
    EXPECT_GT(takenResult.iterations, 1);
    EXPECT_EQ(takenResult.iterations, systems.freshResult.iterations);
    EXPECT_EQ(reused, systems.fresh);
}

// A right-hand side of denormals (1e-320: light times a phase function's g of 5e-324) underflows p^T A p to zero; the
// step x + inf * 0 made x NaN. The solver stops at the breakdown with x finite, within those magnitudes of the truth.
TEST(Multigrid, ARightHandSideOfDenormalsLeavesTheSolutionFinite) {
    StencilOperator A = ballProblem(6, 1e-3);
    UnwrittenVector<double> b(A.size()), x(A.size(), 0.0);
    for (std::size_t i = 0; i < b.size(); ++i) b[i] = (*A.coord)[i].z() > 3 ? 1e-320 : 0.0;
    const MultigridSolver solver(std::move(A));
    solver.solve(b, x, 1e-7, 100, SubProgress(nullptr, 0, 1));
    for (const double v : x) {
        ASSERT_TRUE(std::isfinite(v));
        EXPECT_LE(std::abs(v), 1e-300);
    }
}

TEST(Multigrid, HonoursCancellation) {
    StencilOperator A = ballProblem(10, 1e-6);
    UnwrittenVector<double> b(A.size(), 1.0), x(A.size(), 0.0);
    const MultigridSolver solver(std::move(A));
    Progress progress;
    progress.cancel();
    EXPECT_THROW(solver.solve(b, x, 1e-12, 100, SubProgress(&progress, 0, 1)), Cancelled);
}

}  // namespace firn
