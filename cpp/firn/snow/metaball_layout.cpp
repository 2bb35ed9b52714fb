#include "firn/snow/metaball_layout.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/geometry/metaball.h"
#include "firn/util/random.h"

namespace firn {

namespace {

// Finds x in [lo, hi] where a decreasing function crosses `target` (bisection: robust, 1e-9 relative).
template <typename F>
double solveDecreasing(F f, double target, double lo, double hi) {
    for (int i = 0; i < 50 && hi - lo > 1e-9 * std::max(1.0, std::abs(hi)); ++i) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > target ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// Heights of a column's layers that put the iso-surface of uniformly covered ground at a given depth,
// tabulated over depth (the settings are the same for every column).
class ColumnTable {
  public:
    struct Column {
        int layers;    // K
        double zLow;   // m, centre height of the lowest layer above the surface (< 0: thin snow)
        double zHigh;  // m, centre height of the highest layer
    };

    ColumnTable(double radius, double areaPerBall, double maxDepth)
        : radius_(radius), area_(areaPerBall), layerStep_(0.5 * radius) {
        singleTop_ = solveDecreasing([&](double z) { return wyvillLayerField(z, radius_, area_); }, kSnowIsoValue, 0.0,
                                     radius_);
        step_ = maxDepth / (kEntries - 1);
        // Nested bisections for each entry (a serial 7 ms, on the way from the landing sites to the voxels).
        table_.resize(kEntries);
        tbb::parallel_for(0, kEntries, [&](int i) { table_[i] = solve(i * step_); });
    }

    Column lookup(double depth) const {
        const double x = depth / step_;
        // NaN or far past the deepest column (a site on a triangle too large for float normals): no snow.
        if (!std::isfinite(x) || x > 2.0 * kEntries) return {0, 0.0, 0.0};
        const int i = static_cast<int>(x);
        if (i < 0 || i + 1 >= kEntries) return solve(depth);
        const Column &a = table_[i], &b = table_[i + 1];
        if (a.layers != b.layers || a.layers != layersFor(depth)) return solve(depth);
        const double w = x - i;
        return {a.layers, (1 - w) * a.zLow + w * b.zLow, (1 - w) * a.zHigh + w * b.zHigh};
    }

  private:
    static constexpr int kEntries = 1024;

    int layersFor(double depth) const {
        return depth <= singleTop_ ? 1 : 1 + static_cast<int>(std::ceil((depth - singleTop_) / layerStep_));
    }

    // Iso-surface height over K evenly spaced layers from 0 to zHigh.
    double isoTop(double zHigh, int layers) const {
        auto field = [&](double z) {
            double sum = 0.0;
            for (int k = 0; k < layers; ++k) sum += wyvillLayerField(z - zHigh * k / (layers - 1), radius_, area_);
            return sum;
        };
        return solveDecreasing(field, kSnowIsoValue, zHigh, zHigh + radius_);
    }

    Column solve(double depth) const {
        const int layers = layersFor(depth);
        if (layers == 1) return {1, depth - singleTop_, depth - singleTop_};
        const double zHigh = solveDecreasing([&](double z) { return -isoTop(z, layers); }, -depth, 0.0, depth);
        return {layers, 0.0, zHigh};
    }

    double radius_, area_, layerStep_, singleTop_ = 0.0, step_ = 0.0;
    std::vector<Column> table_;
};

}  // namespace

double metaballRadius(const MetaballLayoutSettings &s) { return s.spacing * (1.25 + 1.25 * s.smoothness); }

class MetaballColumns::Table : public ColumnTable {
    using ColumnTable::ColumnTable;
};

MetaballColumns::MetaballColumns(const MetaballLayoutSettings &s)
    : settings_(s),
      table_(std::make_unique<Table>(metaballRadius(s), s.spacing * s.spacing, s.depth * (1.0 + 0.5 * s.randomness))) {}

MetaballColumns::~MetaballColumns() = default;

std::vector<Metaball> layoutMetaballs(const std::vector<LandingSite> &sites, const MetaballLayoutSettings &s) {
    return MetaballColumns(s).layout(sites);
}

std::vector<Metaball> MetaballColumns::layout(const std::vector<LandingSite> &sites, std::uint64_t stream) const {
    const MetaballLayoutSettings &s = settings_;
    const double radius = metaballRadius(s);
    const ColumnTable &table = *table_;
    const std::uint64_t streamKey = stream * 0x9E3779B97F4A7C15ull;  // 0 for stream 0: layoutMetaballs's draws

    // A site's draws follow its position, not its index: the sites come in the targets' triangle order.
    auto siteStream = [&](std::size_t i) {
        const glm::vec3 &p = sites[i].position;
        return pointStream(p.x, p.y, p.z);
    };
    auto columnDepth = [&](std::size_t i) {
        Rng rng(s.seed ^ 0x5EEDC0FFEEull ^ streamKey, siteStream(i));
        return s.depth * sites[i].cover * (1.0 + 0.5 * s.randomness * (2.0 * rng.uniform() - 1.0));
    };
    std::vector<std::size_t> offsets(sites.size() + 1, 0);
    tbb::parallel_for(std::size_t(0), sites.size(), [&](std::size_t i) {
        const double d = columnDepth(i);
        // A column whose lowest ball would sit deeper than its radius below the surface leaves no snow.
        const ColumnTable::Column c = table.lookup(d);
        offsets[i + 1] = c.zLow > -radius ? c.layers : 0;
    });
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());

    std::vector<Metaball> balls(offsets.back());
    tbb::parallel_for(std::size_t(0), sites.size(), [&](std::size_t i) {
        const std::size_t count = offsets[i + 1] - offsets[i];
        if (count == 0) return;
        const double d = columnDepth(i);
        const ColumnTable::Column c = table.lookup(d);
        Rng rng(s.seed ^ 0xBA11ull ^ streamKey, siteStream(i));
        for (std::size_t k = 0; k < count; ++k) {
            const double z = count == 1 ? c.zLow : c.zLow + (c.zHigh - c.zLow) * double(k) / double(count - 1);
            const double r = radius * (1.0 + 0.2 * s.randomness * (2.0 * rng.uniform() - 1.0));
            balls[offsets[i] + k] = {sites[i].position + sites[i].normal * float(z), float(r), sites[i].normal,
                                     float(z), float(d - z)};
        }
    });
    return balls;
}

}  // namespace firn
