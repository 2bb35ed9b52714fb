#include "firn/spray/emission.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "firn/spray/snow_level_set.h"
#include "firn/util/ceil_count.h"
#include "firn/util/error.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr int kMaxCellsPerSide = 4096;

struct Cell {
    double s0, s1, t0, t1;  // the cell's range of the rectangle's parameters
    std::size_t count;      // lumps it throws
};

std::uint64_t cellStream(std::uint64_t emitter, std::uint64_t cell) { return mix64(emitter) ^ cell; }

// Cells along a side `length` m long: a side a whole number of cells long, to 1e-4 cell, gets that many. One cell
// more for a rounding would give every cell, and every lump after it, other random numbers: a 30 cm ski with
// 2 cm cells is 15 cells, whatever the 1e-7 m Blender's float transforms leave on its sides.
int cellsAlong(double length, double cellSize) { return ceilCount(length / cellSize - 1e-4, kMaxCellsPerSide); }

}  // namespace

void EmissionSettings::validate() const {
    const auto check = [](bool ok, const char *what) {
        if (!ok) throw InvalidArgument(std::string("spray emission settings: ") + what);
    };
    check(rate >= 0.0 && rate < 1e9, "rate must be between 0 and 1e9 lumps per m^3 swept");
    check(spreadAngle >= 0.0 && spreadAngle <= kPi, "spread angle must be between 0 and pi rad");
    check(throwSpeed >= 0.0 && throwSpeed < 100.0, "throw speed must be between 0 and 100 times the emitter's");
    check(cellSize > 1e-4 && cellSize < 100.0, "cell size must be between 0.1 mm and 100 m");
}

SprayParticles emitLumps(const EmitterRectangle &from, const EmitterRectangle &to, double dt,
                         const openvdb::FloatGrid &surface, const glm::dvec3 &down, const EmissionSettings &e,
                         const LumpSettings &lumps, std::uint64_t seed, std::uint64_t emitterIndex,
                         std::uint64_t stepIndex, std::uint64_t &nextId, std::size_t maxNew) {
    const int nu = cellsAlong(2.0 * glm::length(from.halfU), e.cellSize);
    const int nv = cellsAlong(2.0 * glm::length(from.halfV), e.cellSize);
    const double cellArea = from.area() / (double(nu) * nv);  // m^2
    std::vector<Cell> cells(std::size_t(nu) * nv);
    const SnowSampler phi(surface);
    tbb::parallel_for(std::size_t(0), cells.size(), [&](std::size_t c) {
        const int iu = int(c % nu), iv = int(c / nu);
        Cell &cell = cells[c];
        cell = {-1.0 + 2.0 * iu / nu, -1.0 + 2.0 * (iu + 1) / nu, -1.0 + 2.0 * iv / nv, -1.0 + 2.0 * (iv + 1) / nv, 0};
        const double s = 0.5 * (cell.s0 + cell.s1), t = 0.5 * (cell.t0 + cell.t1);
        const glm::dvec3 p = from.pointAt(s, t);
        if (snowLevelSetAt(phi, p) >= 0.0) return;
        const double speed = glm::length(to.pointAt(s, t) - p) / dt;  // m/s
        const double expected = e.rate * speed * dt * cellArea;
        Rng rng = sprayRng(seed, SprayStream::Emission, cellStream(emitterIndex, c), stepIndex);
        // A count over the budget is cut to one over it before it becomes an integer: an emitter moved by 1e30 m in a
        // frame asked for more than a size_t holds, and the wrapped sum left the lumps' array too short.
        const double count = std::floor(expected + rng.uniform()), over = double(maxNew) + 1.0;
        cell.count = count < over ? std::size_t(count) : std::size_t(over);
    });
    // Summed until over the budget (each count is at most one over it, so the sum cannot wrap).
    std::vector<std::size_t> first(cells.size() + 1, 0);
    for (std::size_t c = 0; c < cells.size(); ++c)
        if ((first[c + 1] = first[c] + cells[c].count) > maxNew)
            throw BudgetExceeded("emitter " + std::to_string(emitterIndex) + " would throw more than " +
                                 std::to_string(maxNew) + " lumps in one sub-step, the particle budget left: lower " +
                                 "the emission rate or raise the budget");
    SprayParticles out(first.back());
    const glm::dvec3 up = -down;
    const double cosSpread = std::cos(e.spreadAngle);
    tbb::parallel_for(std::size_t(0), cells.size(), [&](std::size_t c) {
        const Cell &cell = cells[c];
        if (cell.count == 0) return;
        Rng rng = sprayRng(seed, SprayStream::Emission, cellStream(emitterIndex, c), stepIndex);
        rng.uniform();  // the count's draw
        for (std::size_t n = 0; n < cell.count; ++n) {
            const double s = cell.s0 + (cell.s1 - cell.s0) * rng.uniform();
            const double t = cell.t0 + (cell.t1 - cell.t0) * rng.uniform();
            const glm::dvec3 p = from.pointAt(s, t);
            const glm::dvec3 velocity = (to.pointAt(s, t) - p) / dt;  // m/s of that point of the rectangle
            const double u1 = rng.uniform(), u2 = rng.uniform();
            const glm::dvec3 thrown = velocity + e.throwSpeed * glm::length(velocity) *
                                                     sampleUniformCone(up, cosSpread, u1, u2);
            out[first[c] + n] = makeLump(p, thrown, nextId + first[c] + n, lumps, rng);
        }
    });
    nextId += first.back();
    return out;
}

}  // namespace firn
