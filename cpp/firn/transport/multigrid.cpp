#include "firn/transport/multigrid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "firn/transport/voxel_blocks.h"
#include "firn/util/cholesky.h"
#include "firn/util/error.h"

namespace firn {

namespace {

constexpr std::size_t kDenseLimit = 512;  // rows solved directly at the bottom of the hierarchy
constexpr int kSweeps = 2;                // red-black Gauss-Seidel sweeps before and after the coarse solve
constexpr std::size_t kChunk = 8192;      // rows grouped by colour within each run of this many (Level)

template <typename Body>
void parallelRows(std::size_t n, const Body &body) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto &range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) body(i);
    });
}

}  // namespace

template <typename T>
T Stencil<T>::row(std::size_t i, const T *x) const {
    // the row's arrays taken before the links' branches (read inside them, their addresses were reloaded per link)
    const std::array<std::int32_t, 6> &N = (*neighbour)[i];
    const std::array<T, 6> &c = conductance[i];
    T sum = diag[i] * x[i];
    for (int k = 0; k < 6; ++k)
        if (N[k] >= 0) sum -= c[k] * x[N[k]];
    return sum;
}

template <typename T>
void Stencil<T>::apply(const T *x, T *y) const {
    parallelRows(size(), [&](std::size_t i) { y[i] = row(i, x); });
}
template struct Stencil<double>;
template struct Stencil<float>;

struct MultigridSolver::Hierarchy {
    struct Level {
        // A swept level's rows are grouped by colour, a colour being its voxels' parity (i + j + k) & 1, within
        // each chunk of kChunk rows as built: chunk q's colour 0 rows first, up to colourSplit[q], then its colour 1
        // rows, each colour's in the order they were built in. So a colour's sweep streams its own rows' arrays, not
        // every row's to update half of them (a colour's rows read only the other's: the order they are visited in
        // does not matter), and the coefficients are regrouped in place, a chunk at a time. A bottom solved densely
        // keeps its order, the one its factor was computed in.
        Stencil<float> A;
        std::vector<std::uint32_t> colourSplit;
        // The next level's blocks in the order they were built (the order of their members here, so that the loops
        // over them stream these rows) -> rows here (CSR), and each block's row in the next level.
        std::vector<std::uint32_t> membersStart, members, blockRow;
        mutable UnwrittenVector<float> b, x;  // written before they are read (sweep's fromZero)
    };
    std::vector<Level> levels;
    // The caller's neighbour table (its rows', conjugate gradients' order; levels.front() holds the caller's
    // coefficients regrouped, with its own table), and each of the caller's rows' row in levels.front(). A solver
    // takes the levels over only for the same table (another's colours would let a sweep's rows read each other).
    std::shared_ptr<const Stencil<float>::Neighbours> fineNeighbour;
    UnwrittenVector<std::uint32_t> colourRow;
    std::vector<double> cholesky;  // lower factor of the bottom level, dense row-major
    UnwrittenVector<float> remainder;  // finest level: diag minus the conductances

    // fromZero: the first sweep of a cycle, whose neighbours all hold x = 0 (they are not read; the level's x need
    // not be cleared first: the other colour's sweep writes the rest before anything reads it).
    void sweep(const Level &level, int colour, bool fromZero = false) const {
        const Stencil<float> &A = level.A;
        const Stencil<float>::Neighbours &N = *A.neighbour;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, level.colourSplit.size(), 1), [&](const auto &chunks) {
            for (std::size_t q = chunks.begin(); q != chunks.end(); ++q) {
                const std::size_t split = level.colourSplit[q];
                const std::size_t end = colour == 0 ? split : std::min(A.size(), (q + 1) * kChunk);
                for (std::size_t i = colour == 0 ? q * kChunk : split; i != end; ++i) {
                    // the row's arrays taken before the branches (read inside them, their addresses were reloaded
                    // per link: the stores to x might alias them)
                    const std::array<std::int32_t, 6> &neighbour = N[i];
                    const std::array<float, 6> &conductance = A.conductance[i];
                    const float *x = level.x.data();
                    float sum = level.b[i];
                    for (int k = 0; k < 6 && !fromZero; ++k)
                        if (neighbour[k] >= 0) sum += conductance[k] * x[neighbour[k]];
                    level.x[i] = sum / A.diag[i];
                }
            }
        });
    }

    void solveDense(const Level &level) const {
        std::vector<double> x(level.b.begin(), level.b.end());
        choleskySolve(cholesky.data(), x.size(), x.data());
        std::copy(x.begin(), x.end(), level.x.begin());
    }

    // One V-cycle on level l for level.b, from x = 0; symmetric (post-smoothing is the adjoint).
    void vcycle(std::size_t l) const {
        const Level &level = levels[l];
        if (l + 1 == levels.size()) {
            if (!cholesky.empty()) return solveDense(level);
            for (int s = 0; s < 50; ++s) sweep(level, 0, s == 0), sweep(level, 1);
            for (int s = 0; s < 50; ++s) sweep(level, 1), sweep(level, 0);
            return;
        }
        for (int s = 0; s < kSweeps; ++s) sweep(level, 0, s == 0), sweep(level, 1);
        const Level &coarse = levels[l + 1];
        // The residual b - A x restricted to the blocks and the correction brought back, block by block (the
        // residual is not stored: 4 bytes per row).
        parallelRows(coarse.A.size(), [&](std::size_t I) {
            double sum = 0.0;
            for (std::uint32_t m = level.membersStart[I]; m < level.membersStart[I + 1]; ++m)
                sum += level.b[level.members[m]] - level.A.row(level.members[m], level.x.data());
            coarse.b[level.blockRow[I]] = sum;
        });
        vcycle(l + 1);
        parallelRows(coarse.A.size(), [&](std::size_t I) {
            for (std::uint32_t m = level.membersStart[I]; m < level.membersStart[I + 1]; ++m)
                level.x[level.members[m]] += coarse.x[level.blockRow[I]];
        });
        for (int s = 0; s < kSweeps; ++s) sweep(level, 1), sweep(level, 0);
    }
};

namespace {

using Level = MultigridSolver::Hierarchy::Level;

// Each row's new row, grouped by colour within its chunk (Level::colourSplit), each colour's rows in their order.
UnwrittenVector<std::uint32_t> colourOrder(const Stencil<float>::Voxels &coord, std::vector<std::uint32_t> &split) {
    const auto colour = [](const openvdb::Coord &c) { return (c.x() + c.y() + c.z()) & 1; };
    split.resize((coord.size() + kChunk - 1) / kChunk);
    UnwrittenVector<std::uint32_t> row(coord.size());
    parallelRows(split.size(), [&](std::size_t q) {
        const std::size_t begin = q * kChunk, end = std::min(coord.size(), begin + kChunk);
        std::size_t colour0 = 0;
        for (std::size_t i = begin; i < end; ++i) colour0 += colour(coord[i]) == 0;
        std::array<std::uint32_t, 2> next{std::uint32_t(begin), std::uint32_t(begin + colour0)};
        for (std::size_t i = begin; i < end; ++i) row[i] = next[colour(coord[i])]++;
        split[q] = next[0];
    });
    return row;
}

// A's conductances and diagonal regrouped in place: each row i's moved to row[i], within its chunk.
void regroupCoefficients(Stencil<float> &A, const UnwrittenVector<std::uint32_t> &row) {
    parallelRows((A.size() + kChunk - 1) / kChunk, [&](std::size_t q) {
        const std::size_t begin = q * kChunk, end = std::min(A.size(), begin + kChunk);
        const std::vector<std::array<float, 6>> conductance(A.conductance.begin() + begin, A.conductance.begin() + end);
        const std::vector<float> diag(A.diag.begin() + begin, A.diag.begin() + end);
        for (std::size_t i = begin; i < end; ++i)
            A.conductance[row[i]] = conductance[i - begin], A.diag[row[i]] = diag[i - begin];
    });
}

// A level's rows regrouped (`row`: each row's new row): its operator (a neighbour table of its own), its rows as
// members of the next level's blocks, and the rows of the finer level's blocks (given one). The blocks keep their
// members and the order they were built in, so that every sum over them is added as before.
void regroup(Level &level, const UnwrittenVector<std::uint32_t> &row, Level *finer) {
    const Stencil<float>::Neighbours &N = *level.A.neighbour;
    auto neighbour = std::make_shared<Stencil<float>::Neighbours>(N.size());
    parallelRows(N.size(), [&](std::size_t i) {
        for (int k = 0; k < 6; ++k) (*neighbour)[row[i]][k] = N[i][k] >= 0 ? std::int32_t(row[N[i][k]]) : N[i][k];
    });
    level.A.neighbour = std::move(neighbour);
    regroupCoefficients(level.A, row);
    parallelRows(level.members.size(), [&](std::size_t m) { level.members[m] = row[level.members[m]]; });
    level.b.resize(row.size()), level.x.resize(row.size());
    if (finer)
        parallelRows(finer->blockRow.size(), [&](std::size_t I) { finer->blockRow[I] = row[finer->blockRow[I]]; });
}

// The next level's rows: 2x2x2 blocks of this one's voxels (fine.members, coarse's voxels; `block`: each fine row's
// block, its row there); returns false when that would barely shrink it.
bool aggregate(Level &fine, Level &coarse, UnwrittenVector<std::uint32_t> &block) {
    VoxelBlocks blocks = voxelBlocks(*fine.A.coord);
    const std::size_t nc = blocks.coord.size();
    coarse.A.coord = std::make_shared<Stencil<float>::Voxels>(std::move(blocks.coord));
    if (nc > fine.A.size() * 3 / 4) return false;
    block = std::move(blocks.ofRow);
    fine.membersStart = std::move(blocks.membersStart), fine.members = std::move(blocks.members);
    fine.blockRow.resize(nc);
    std::iota(fine.blockRow.begin(), fine.blockRow.end(), 0u);
    return true;
}

// Each fine row's block (its row on the next level), from the blocks' members.
UnwrittenVector<std::uint32_t> blockOfRows(const Level &fine) {
    UnwrittenVector<std::uint32_t> block(fine.A.size());
    parallelRows(fine.membersStart.size() - 1, [&](std::size_t I) {
        for (std::uint32_t m = fine.membersStart[I]; m < fine.membersStart[I + 1]; ++m)
            block[fine.members[m]] = std::uint32_t(I);
    });
    return block;
}

// The next level's operator summed from this one's over its blocks (`block`: each fine row's, as built; written to
// the blocks' rows), and where `neighbour` is given (a fresh build; levels taken over have theirs) the next level's
// neighbours.
void sumCoarseOperator(const Level &fine, const UnwrittenVector<std::uint32_t> &block, Level &coarse,
                       Stencil<float>::Neighbours *neighbour) {
    const Stencil<float> &A = fine.A;
    const Stencil<float>::Neighbours &N = *A.neighbour;
    const std::size_t nc = fine.membersStart.size() - 1;
    Stencil<float> &C = coarse.A;
    C.conductance.resize(nc), C.diag.resize(nc);  // every row written below
    // A block's neighbour along an axis is the block its members' links on that side cross into (a voxel's
    // neighbour one step away lies in its own block or in the next one that way). A neighbouring block that no
    // link reaches gets none: its conductance would be 0, which adds nothing to a sum.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nc, 1024), [&](const auto &range) {
        for (std::size_t I = range.begin(); I != range.end(); ++I) {
            double remainder = 0.0;  // sums in double, stored in float
            std::array<double, 6> crossing{};
            std::array<std::int32_t, 6> across;
            across.fill(Stencil<float>::kNone);
            for (std::uint32_t m = fine.membersStart[I]; m < fine.membersStart[I + 1]; ++m) {
                const std::uint32_t i = fine.members[m];
                remainder += A.diag[i];
                for (int k = 0; k < 6; ++k) {
                    const std::int32_t j = N[i][k];
                    if (j < 0) continue;
                    remainder -= A.conductance[i][k];
                    if (block[j] != I) crossing[k] += A.conductance[i][k], across[k] = std::int32_t(block[j]);
                }
            }
            const std::uint32_t row = fine.blockRow[I];
            double diag = remainder;
            for (int k = 0; k < 6; ++k) {
                if (neighbour)
                    (*neighbour)[row][k] = across[k] < 0 ? across[k] : std::int32_t(fine.blockRow[across[k]]);
                C.conductance[row][k] = float(across[k] < 0 ? 0.0 : 0.5 * crossing[k]);
                diag += C.conductance[row][k];
            }
            C.diag[row] = float(diag);
        }
    });
}

// The next level: 2x2x2 blocks of this one; returns false when that would barely shrink it.
bool coarsen(Level &fine, Level &coarse) {
    UnwrittenVector<std::uint32_t> block;
    if (!aggregate(fine, coarse, block)) return false;
    auto neighbour = std::make_shared<Stencil<float>::Neighbours>(fine.membersStart.size() - 1);
    sumCoarseOperator(fine, block, coarse, neighbour.get());
    coarse.A.neighbour = std::move(neighbour);
    return true;
}

std::vector<double> denseCholesky(const Stencil<float> &A) {
    const std::size_t n = A.size();
    std::vector<double> L(n * n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        L[i * n + i] = A.diag[i];
        for (int k = 0; k < 6; ++k)
            if ((*A.neighbour)[i][k] >= 0) L[i * n + (*A.neighbour)[i][k]] -= A.conductance[i][k];
    }
    if (!choleskyFactor(L.data(), n))  // seen with voxels thousands of mean free paths thick: exp(-tau) underflows
        throw InvalidArgument("the diffusion solve broke down (coarse operator not positive definite): the snow "
                              "is too optically thick per voxel; use a smaller voxel size");
    return L;
}

// The operator for conjugate gradients: the finest level's single-precision coefficients, applied in double
// precision (the coefficients' rounding perturbs the system by 1e-7, far below the solve's tolerance; one copy of
// the operator serves both the iteration and its preconditioner).
struct FineOperator {
    const MultigridSolver::Hierarchy &h;  // the finest level's coefficients (at h.colourRow), the caller's rows
    const UnwrittenVector<float> &remainder;  // diag - sum of conductances: the absorption and boundary terms
    // remainder x_i + sum_k c_ik (x_i - x_k): the same operator, without the rounding of a large diagonal
    // swamping a small absorption (clean snow's blue: 1e-5 of the diagonal).
    void multiply(const double *x, double *y) const {
        const Stencil<float>::Neighbours &N = *h.fineNeighbour;
        parallelRows(N.size(), [&](std::size_t i) {
            // the row's arrays taken before the branches (read inside them, their addresses were reloaded per link)
            const std::array<std::int32_t, 6> &neighbour = N[i];
            const std::array<float, 6> &conductance = h.levels.front().A.conductance[h.colourRow[i]];
            double sum = double(remainder[i]) * x[i];
            for (int k = 0; k < 6; ++k)
                if (neighbour[k] >= 0) sum += double(conductance[k]) * (x[i] - x[neighbour[k]]);
            y[i] = sum;
        });
    }
};

// Conjugate gradients' reductions as OpenVDB's pcg::Vector computes them, so that the iterates are those of its
// pcg::solve bit for bit: <a, b> summed in 100 fixed segments added in order (serially below 1024 entries), the
// same whatever the threads; the largest |a_i|.
// `segment(s, begin, end)` returns segment s's part of the sum; called once per segment, in parallel.
constexpr std::size_t kSegments = 100;
template <typename Segment>
double segmentedSum(std::size_t n, const Segment &segment) {
    if (n < 1024) return segment(std::size_t(0), std::size_t(0), n);
    std::array<double, kSegments> partial;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, kSegments), [&](const auto &range) {
        for (std::size_t s = range.begin(); s != range.end(); ++s) {
            const std::size_t begin = s * (n / kSegments), end = s + 1 == kSegments ? n : begin + n / kSegments;
            partial[s] = segment(s, begin, end);
        }
    });
    double sum = 0.0;
    for (double part : partial) sum += part;
    return sum;
}
// (Vectors: the caller's b and x, the workspace's p and z.)
double dot(const UnwrittenVector<double> &a, const UnwrittenVector<double> &b) {
    return segmentedSum(a.size(), [&](std::size_t, std::size_t begin, std::size_t end) {
        double part = 0.0;
        for (std::size_t i = begin; i < end; ++i) part += a[i] * b[i];
        return part;
    });
}
double infNorm(const UnwrittenVector<double> &a) {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, a.size()), 0.0,
        [&](const auto &range, double most) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) most = std::max(most, std::abs(a[i]));
            return most;
        },
        [](double a, double b) { return std::max(a, b); });
}
// z = one V-cycle applied to r, scaled into float's range (the bake's sources span many decades between scenes) by
// r's largest |r_i|.
void precondition(const MultigridSolver::Hierarchy &hierarchy, const UnwrittenVector<double> &r, double largest,
                  UnwrittenVector<double> &z) {
    const auto &top = hierarchy.levels.front();
    const UnwrittenVector<std::uint32_t> &row = hierarchy.colourRow;
    const double scale = std::max(largest, 1e-300);
    parallelRows(row.size(), [&](std::size_t i) { top.b[row[i]] = float(r[i] / scale); });
    hierarchy.vcycle(0);
    parallelRows(row.size(), [&](std::size_t i) { z[i] = double(top.x[row[i]]) * scale; });
}

// y = a x + y.
void axpy(double a, const UnwrittenVector<double> &x, UnwrittenVector<double> &y) {
    parallelRows(y.size(), [&](std::size_t i) { y[i] = a * x[i] + y[i]; });
}

// The iteration's step in one pass over the vectors: x += alpha p, r -= alpha q; returns <r, r> (as dot) and sets
// `largest` to the largest |r_i| of the new r.
double step(double alpha, const UnwrittenVector<double> &p, const UnwrittenVector<double> &q,
            UnwrittenVector<double> &x, UnwrittenVector<double> &r, double &largest) {
    std::array<double, kSegments> most{};  // per segment of segmentedSum
    const double sum = segmentedSum(r.size(), [&](std::size_t s, std::size_t begin, std::size_t end) {
        double part = 0.0, top = 0.0;
        for (std::size_t i = begin; i < end; ++i) {
            x[i] = alpha * p[i] + x[i];
            r[i] = -alpha * q[i] + r[i];
            part += r[i] * r[i];
            top = std::max(top, std::abs(r[i]));
        }
        most[s] = top;
        return part;
    });
    largest = *std::max_element(most.begin(), most.end());
    return sum;
}

}  // namespace

namespace {

// Every row's remainder (rowRemainder), stored in float.
UnwrittenVector<float> remainderOf(const StencilOperator &A) {
    UnwrittenVector<float> out(A.size());
    parallelRows(A.size(), [&](std::size_t i) { out[i] = float(rowRemainder(A.diag[i], A.conductance[i], (*A.neighbour)[i])); });
    return out;
}

Stencil<float> singlePrecision(const StencilOperator &A) {
    Stencil<float> out;
    out.coord = A.coord, out.neighbour = A.neighbour;
    out.conductance.resize(A.size()), out.diag.resize(A.size());
    parallelRows(A.size(), [&](std::size_t i) {
        for (int k = 0; k < 6; ++k) out.conductance[i][k] = float(A.conductance[i][k]);
        out.diag[i] = float(A.diag[i]);
    });
    return out;
}

}  // namespace

MultigridSolver::MultigridSolver(StencilOperator fine) : MultigridSolver(singlePrecision(fine), remainderOf(fine)) {}

MultigridSolver::MultigridSolver(Stencil<float> fine, UnwrittenVector<float> remainder, Workspace *workspace) {
    const bool takeOver = workspace && workspace->levels && workspace->levels->fineNeighbour == fine.neighbour;
    hierarchy_ = takeOver ? std::move(workspace->levels) : std::make_shared<Hierarchy>();
    Hierarchy &h = *hierarchy_;
    h.remainder = std::move(remainder);
    if (takeOver) {
        // The levels' rows, blocks and colours as they were: only the operators are regrouped and summed again
        // (their vectors b and x are written before they are read).
        Stencil<float> &top = h.levels.front().A;
        top.conductance = std::move(fine.conductance), top.diag = std::move(fine.diag);
        regroupCoefficients(top, h.colourRow);
        for (std::size_t l = 0; l + 1 < h.levels.size(); ++l)
            sumCoarseOperator(h.levels[l], blockOfRows(h.levels[l]), h.levels[l + 1], nullptr);
    } else {
        // Built in the caller's rows, then regrouped by colour: the same blocks, sums and factor as built.
        h.fineNeighbour = fine.neighbour;
        h.levels.emplace_back();
        h.levels.back().A = std::move(fine);
        while (h.levels.back().A.size() > kDenseLimit) {
            Level next;
            if (!coarsen(h.levels.back(), next)) break;
            h.levels.push_back(std::move(next));
        }
        const bool denseBottom = h.levels.back().A.size() <= kDenseLimit;
        for (std::size_t l = 0; l < h.levels.size(); ++l) {
            Level &level = h.levels[l];
            UnwrittenVector<std::uint32_t> row;
            if (denseBottom && l + 1 == h.levels.size()) row.resize(level.A.size()), std::iota(row.begin(), row.end(), 0u);
            else row = colourOrder(*level.A.coord, level.colourSplit);
            regroup(level, row, l == 0 ? nullptr : &h.levels[l - 1]);
            if (l == 0) h.colourRow = std::move(row);
        }
    }
    h.cholesky.clear();
    if (h.levels.back().A.size() <= kDenseLimit) h.cholesky = denseCholesky(h.levels.back().A);
    for (Level &level : h.levels) level.A.coord.reset();  // they only placed the rows in colours and blocks
}

MultigridSolver::~MultigridSolver() = default;

int MultigridSolver::levelCount() const { return int(hierarchy_->levels.size()); }

std::pair<Stencil<float>, UnwrittenVector<float>> MultigridSolver::release(Workspace *workspace) && {
    // The coefficients' storage, regrouped (the caller writes every row afresh), under the caller's table; the
    // finest level keeps its own.
    Stencil<float> &top = hierarchy_->levels.front().A;
    std::pair<Stencil<float>, UnwrittenVector<float>> out;
    out.first.neighbour = hierarchy_->fineNeighbour;
    out.first.conductance = std::move(top.conductance), out.first.diag = std::move(top.diag);
    out.second = std::move(hierarchy_->remainder);
    if (workspace) workspace->levels = std::move(hierarchy_);
    hierarchy_.reset();
    return out;
}

MultigridSolver::Result MultigridSolver::solve(UnwrittenVector<double> b, UnwrittenVector<double> &x,
                                               double relativeTolerance, int maxIterations,
                                               const SubProgress &progress, Workspace *workspace) const {
    Workspace local;
    Workspace &w = workspace ? *workspace : local;
    const Result result = iterate(b, x, relativeTolerance, maxIterations, progress, w);
    w.spare = std::move(b);
    return result;
}

MultigridSolver::Result MultigridSolver::iterate(UnwrittenVector<double> &b, UnwrittenVector<double> &x,
                                                 double relativeTolerance, int maxIterations,
                                                 const SubProgress &progress, Workspace &w) const {
    const std::size_t n = b.size();
    if (x.size() != n || hierarchy_->levels.front().A.size() != n)
        throw InvalidArgument("multigrid solve: the operator, b and x differ in size");
    Result result;
    if (n == 0) return result;
    // Preconditioned conjugate gradients, the steps of OpenVDB's pcg::solve in its order (the same iterates), in
    // b and x rather than in copies: r takes b's place, A p takes z's (32 bytes per unknown, against 48). p and z
    // are written before they are read, so a workspace's earlier values do not matter.
    const FineOperator A{*hierarchy_, hierarchy_->remainder};
    const double tolerance = std::max(relativeTolerance, kFinestTolerance);
    const double largestB = infNorm(b), normB = largestB == 0.0 ? 1.0 : largestB;
    w.p.resize(n), w.z.resize(n);
    UnwrittenVector<double> &r = b;
    UnwrittenVector<double> &p = w.p, &z = w.z;  // z: M^-1 r, then A p
    A.multiply(x.data(), z.data());
    axpy(-1.0, z, r);  // r = b - A x
    double largest = infNorm(r);
    result.relativeResidual = largest / normB;
    if (result.relativeResidual <= tolerance) return result;
    double rDotZPrevious = 1.0, leastL2 = std::numeric_limits<double>::max();
    for (int iteration = 0; iteration < maxIterations; ++iteration) {
        progress.throwIfCancelled();
        result.iterations = iteration + 1;
        precondition(*hierarchy_, r, largest, z);
        const double rDotZ = dot(r, z);
        if (iteration == 0) parallelRows(n, [&](std::size_t i) { p[i] = z[i]; });
        else {
            const double beta = rDotZ / rDotZPrevious;
            parallelRows(n, [&](std::size_t i) { p[i] = beta * p[i] + z[i]; });
        }
        UnwrittenVector<double> &q = z;
        A.multiply(p.data(), q.data());
        const double alpha = rDotZ / dot(p, q);
        // A breakdown: p^T A p underflowed to zero (a right-hand side of 1e-320, from a phase function's g of 5e-324),
        // and x + inf * 0 would be NaN. x stays as it is, as close as those magnitudes allow.
        if (!std::isfinite(alpha)) break;
        rDotZPrevious = rDotZ;
        const double l2 = std::sqrt(step(alpha, p, q, x, r, largest));
        leastL2 = std::min(l2, leastL2);
        result.relativeResidual = largest / normB;
        // Diverging, not finite, or converged.
        if (l2 > 2.0 * leastL2 || !std::isfinite(largest) || result.relativeResidual <= tolerance) break;
    }
    return result;
}

}  // namespace firn
