#include "firn/transport/multigrid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/error.h"

namespace firn {

namespace {

using Matrix = openvdb::math::pcg::SparseStencilMatrix<double, 7>;
using PcgVector = openvdb::math::pcg::Vector<double>;

constexpr std::size_t kDenseLimit = 512;  // rows solved directly at the bottom of the hierarchy
constexpr int kSweeps = 2;                // red-black Gauss-Seidel sweeps before and after the coarse solve

int floorHalf(int v) { return v >= 0 ? v / 2 : -((-v + 1) / 2); }

template <typename Body>
void parallelRows(std::size_t n, const Body &body) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto &range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) body(i);
    });
}

}  // namespace

template <typename T>
void Stencil<T>::apply(const T *x, T *y) const {
    parallelRows(size(), [&](std::size_t i) {
        T sum = diag[i] * x[i];
        for (int k = 0; k < 6; ++k)
            if (neighbour[i][k] != kNone) sum -= conductance[i][k] * x[neighbour[i][k]];
        y[i] = sum;
    });
}
template struct Stencil<double>;
template struct Stencil<float>;

struct MultigridSolver::Hierarchy {
    struct Level {
        Stencil<float> A;
        std::vector<std::uint32_t> rowsByColour[2];  // voxel parity (i + j + k) & 1
        std::vector<std::uint32_t> aggregate;        // row -> row of the next level
        std::vector<std::uint32_t> membersStart, members;  // next level's rows -> rows here (CSR)
        mutable std::vector<float> b, x, r;
    };
    std::vector<Level> levels;
    std::vector<double> cholesky;  // lower factor of the bottom level, dense row-major
    std::vector<float> remainder;  // finest level: diag minus the conductances

    void sweep(const Level &level, int colour) const {
        const Stencil<float> &A = level.A;
        const auto &rows = level.rowsByColour[colour];
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.size(), 4096), [&](const auto &range) {
            for (std::size_t n = range.begin(); n != range.end(); ++n) {
                const std::uint32_t i = rows[n];
                float sum = level.b[i];
                for (int k = 0; k < 6; ++k)
                    if (A.neighbour[i][k] != StencilOperator::kNone)
                        sum += A.conductance[i][k] * level.x[A.neighbour[i][k]];
                level.x[i] = sum / A.diag[i];
            }
        });
    }

    void solveDense(const Level &level) const {
        const std::size_t n = level.A.size();
        std::vector<double> x(n);
        for (std::size_t i = 0; i < n; ++i) {  // L y = b
            double s = level.b[i];
            for (std::size_t k = 0; k < i; ++k) s -= cholesky[i * n + k] * x[k];
            x[i] = s / cholesky[i * n + i];
        }
        for (std::size_t i = n; i-- > 0;) {  // L^T x = y
            double s = x[i];
            for (std::size_t k = i + 1; k < n; ++k) s -= cholesky[k * n + i] * x[k];
            x[i] = s / cholesky[i * n + i];
        }
        std::copy(x.begin(), x.end(), level.x.begin());
    }

    // One V-cycle on level l for level.b, from x = 0; symmetric (post-smoothing is the adjoint).
    void vcycle(std::size_t l) const {
        const Level &level = levels[l];
        std::fill(level.x.begin(), level.x.end(), 0.0);
        if (l + 1 == levels.size()) {
            if (!cholesky.empty()) return solveDense(level);
            for (int s = 0; s < 50; ++s) sweep(level, 0), sweep(level, 1);
            for (int s = 0; s < 50; ++s) sweep(level, 1), sweep(level, 0);
            return;
        }
        for (int s = 0; s < kSweeps; ++s) sweep(level, 0), sweep(level, 1);
        level.A.apply(level.x.data(), level.r.data());
        const Level &coarse = levels[l + 1];
        parallelRows(coarse.A.size(), [&](std::size_t I) {
            double sum = 0.0;
            for (std::uint32_t m = level.membersStart[I]; m < level.membersStart[I + 1]; ++m)
                sum += level.b[level.members[m]] - level.r[level.members[m]];
            coarse.b[I] = sum;
        });
        vcycle(l + 1);
        parallelRows(level.A.size(), [&](std::size_t i) { level.x[i] += coarse.x[level.aggregate[i]]; });
        for (int s = 0; s < kSweeps; ++s) sweep(level, 1), sweep(level, 0);
    }
};

namespace {

using Level = MultigridSolver::Hierarchy::Level;

void prepare(Level &level) {
    const std::size_t n = level.A.size();
    level.rowsByColour[0].clear(), level.rowsByColour[1].clear();
    for (std::size_t i = 0; i < n; ++i) {
        const openvdb::Coord &c = level.A.coord[i];
        level.rowsByColour[(c.x() + c.y() + c.z()) & 1].push_back(std::uint32_t(i));
    }
    level.b.assign(n, 0.0), level.x.assign(n, 0.0), level.r.assign(n, 0.0);
}

// The next level: 2x2x2 blocks of this one; returns false when that would barely shrink it.
bool coarsen(Level &fine, Level &coarse) {
    const Stencil<float> &A = fine.A;
    const std::size_t n = A.size();
    openvdb::Int32Tree index(-1);
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> access(index);
    fine.aggregate.resize(n);
    Stencil<float> &C = coarse.A;
    for (std::size_t i = 0; i < n; ++i) {
        const openvdb::Coord &c = A.coord[i];
        const openvdb::Coord cc(floorHalf(c.x()), floorHalf(c.y()), floorHalf(c.z()));
        int id = access.getValue(cc);
        if (id < 0) {
            id = int(C.coord.size());
            access.setValue(cc, id);
            C.coord.push_back(cc);
        }
        fine.aggregate[i] = std::uint32_t(id);
    }
    const std::size_t nc = C.coord.size();
    if (nc > n * 3 / 4) return false;
    using StencilOperator = Stencil<float>;

    // Members of each block, in fine order (CSR).
    fine.membersStart.assign(nc + 1, 0);
    for (std::uint32_t a : fine.aggregate) ++fine.membersStart[a + 1];
    for (std::size_t I = 0; I < nc; ++I) fine.membersStart[I + 1] += fine.membersStart[I];
    fine.members.resize(n);
    std::vector<std::uint32_t> fill(fine.membersStart.begin(), fine.membersStart.end() - 1);
    for (std::size_t i = 0; i < n; ++i) fine.members[fill[fine.aggregate[i]]++] = std::uint32_t(i);

    C.neighbour.assign(nc, {});
    C.conductance.assign(nc, {});
    C.diag.assign(nc, 0.0);
    static const openvdb::Coord kStep[6] = {openvdb::Coord(-1, 0, 0), openvdb::Coord(1, 0, 0),
                                            openvdb::Coord(0, -1, 0), openvdb::Coord(0, 1, 0),
                                            openvdb::Coord(0, 0, -1), openvdb::Coord(0, 0, 1)};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nc, 1024), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> look(index);
        for (std::size_t I = range.begin(); I != range.end(); ++I) {
            double remainder = 0.0;  // sums in double, stored in float
            std::array<double, 6> crossing{};
            for (std::uint32_t m = fine.membersStart[I]; m < fine.membersStart[I + 1]; ++m) {
                const std::uint32_t i = fine.members[m];
                remainder += A.diag[i];
                for (int k = 0; k < 6; ++k) {
                    const std::uint32_t j = A.neighbour[i][k];
                    if (j == StencilOperator::kNone) continue;
                    remainder -= A.conductance[i][k];
                    if (fine.aggregate[j] != I) crossing[k] += A.conductance[i][k];
                }
            }
            double diag = remainder;
            for (int k = 0; k < 6; ++k) {
                const int id = look.getValue(C.coord[I] + kStep[k]);
                C.neighbour[I][k] = id < 0 ? StencilOperator::kNone : std::uint32_t(id);
                C.conductance[I][k] = float(id < 0 ? 0.0 : 0.5 * crossing[k]);
                diag += C.conductance[I][k];
            }
            C.diag[I] = float(diag);
        }
    });
    return true;
}

std::vector<double> denseCholesky(const Stencil<float> &A) {
    const std::size_t n = A.size();
    std::vector<double> L(n * n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        L[i * n + i] = A.diag[i];
        for (int k = 0; k < 6; ++k)
            if (A.neighbour[i][k] != StencilOperator::kNone) L[i * n + A.neighbour[i][k]] -= A.conductance[i][k];
    }
    for (std::size_t j = 0; j < n; ++j) {
        double d = L[j * n + j];
        for (std::size_t k = 0; k < j; ++k) d -= L[j * n + k] * L[j * n + k];
        if (!(d > 0.0))  // seen with voxels thousands of mean free paths thick: exp(-tau) underflows
            throw InvalidArgument("the diffusion solve broke down (coarse operator not positive definite): the snow "
                                  "is too optically thick per voxel; use a smaller voxel size");
        L[j * n + j] = std::sqrt(d);
        for (std::size_t i = j + 1; i < n; ++i) {
            double s = L[i * n + j];
            for (std::size_t k = 0; k < j; ++k) s -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = s / L[j * n + j];
        }
    }
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j) L[i * n + j] = 0.0;
    return L;
}

// The operator for OpenVDB's conjugate gradients: the finest level's single-precision coefficients,
// applied in double precision (the coefficients' rounding perturbs the system by 1e-7, far below the
// solve's tolerance; one copy of the operator serves both the iteration and its preconditioner).
struct FineOperator {
    using ValueType = double;
    const Stencil<float> &A;
    const std::vector<float> &remainder;  // diag - sum of conductances: the absorption and boundary terms
    openvdb::math::pcg::SizeType numRows() const { return openvdb::math::pcg::SizeType(A.size()); }
    // remainder x_i + sum_k c_ik (x_i - x_k): the same operator, without the rounding of a large diagonal
    // swamping a small absorption (clean snow's blue: 1e-5 of the diagonal).
    void vectorMultiply(const double *x, double *y) const {
        parallelRows(A.size(), [&](std::size_t i) {
            double sum = double(remainder[i]) * x[i];
            for (int k = 0; k < 6; ++k)
                if (A.neighbour[i][k] != StencilOperator::kNone) sum += double(A.conductance[i][k]) * (x[i] - x[A.neighbour[i][k]]);
            y[i] = sum;
        });
    }
    void vectorMultiply(const PcgVector &x, PcgVector &y) const { vectorMultiply(x.data(), y.data()); }
};

class VCycle : public openvdb::math::pcg::Preconditioner<double> {
  public:
    explicit VCycle(const MultigridSolver::Hierarchy &hierarchy)
        : openvdb::math::pcg::Preconditioner<double>(Matrix(1)), hierarchy_(hierarchy) {}
    void apply(const PcgVector &r, PcgVector &z) override {
        const auto &top = hierarchy_.levels.front();
        // Scaled into float's range (the bake's sources span many decades between scenes).
        const double scale = std::max(r.infNorm(), 1e-300);
        const double *in = r.data();
        double *out = z.data();
        parallelRows(top.b.size(), [&](std::size_t i) { top.b[i] = float(in[i] / scale); });
        hierarchy_.vcycle(0);
        parallelRows(top.x.size(), [&](std::size_t i) { out[i] = double(top.x[i]) * scale; });
    }

  private:
    const MultigridSolver::Hierarchy &hierarchy_;
};

struct Interrupter {
    const SubProgress *progress;
    void start(const char * = nullptr) {}
    void end() {}
    bool wasInterrupted(int = -1) const {
        try {
            progress->throwIfCancelled();
        } catch (const Cancelled &) {
            return true;
        }
        return false;
    }
};

}  // namespace

namespace {

// Every row's remainder (rowRemainder), stored in float.
std::vector<float> remainderOf(const StencilOperator &A) {
    std::vector<float> out(A.size());
    parallelRows(A.size(), [&](std::size_t i) { out[i] = float(rowRemainder(A.diag[i], A.conductance[i], A.neighbour[i])); });
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

MultigridSolver::MultigridSolver(Stencil<float> fine, std::vector<float> remainder)
    : hierarchy_(std::make_unique<Hierarchy>()) {
    Hierarchy &h = *hierarchy_;
    h.levels.emplace_back();
    h.levels.back().A = std::move(fine);
    h.remainder = std::move(remainder);
    while (h.levels.back().A.size() > kDenseLimit) {
        Level next;
        if (!coarsen(h.levels.back(), next)) break;
        h.levels.push_back(std::move(next));
    }
    for (Level &level : h.levels) prepare(level);
    if (h.levels.back().A.size() <= kDenseLimit) h.cholesky = denseCholesky(h.levels.back().A);
    for (Level &level : h.levels) level.A.coord = std::vector<openvdb::Coord>();  // they only placed the rows in colours and blocks
}

MultigridSolver::~MultigridSolver() = default;

int MultigridSolver::levelCount() const { return int(hierarchy_->levels.size()); }

MultigridSolver::Result MultigridSolver::solve(std::vector<double> b, std::vector<double> &x,
                                               double relativeTolerance, int maxIterations,
                                               const SubProgress &progress) const {
    const std::size_t n = b.size();
    PcgVector bv{openvdb::math::pcg::SizeType(n)}, xv{openvdb::math::pcg::SizeType(n)};
    std::copy(b.begin(), b.end(), bv.data());
    std::copy(x.begin(), x.end(), xv.data());
    // Freed meanwhile (the bake's largest solves: 16 bytes per unknown); `= {}` would keep their capacity.
    b = std::vector<double>(), x = std::vector<double>();
    VCycle preconditioner(*hierarchy_);
    const FineOperator A{hierarchy_->levels.front().A, hierarchy_->remainder};
    openvdb::math::pcg::State termination = openvdb::math::pcg::terminationDefaults<double>();
    termination.iterations = maxIterations;
    termination.relativeError = std::max(relativeTolerance, kFinestTolerance);
    termination.absoluteError = 0.0;
    Interrupter interrupter{&progress};
    openvdb::math::pcg::State state;
    try {
        state = openvdb::math::pcg::solve(A, bv, xv, preconditioner, interrupter, termination);
    } catch (const openvdb::RuntimeError &) {
        progress.throwIfCancelled();
        throw;
    }
    x.assign(xv.data(), xv.data() + n);
    return {state.iterations, state.relativeError};
}

}  // namespace firn
