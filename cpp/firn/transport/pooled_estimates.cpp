#include "firn/transport/pooled_estimates.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/color.h"

namespace firn {

namespace {

// a += w b, the estimate's sums but its cost.
void addScaled(SourceEstimate &a, const SourceEstimate &b, double w) {
    a.l0 += w * b.l0, a.l1 += w * b.l1, a.beamL0 += w * b.beamL0, a.beamL1 += w * b.beamL1, a.second += w * b.second;
    for (int i = 0; i < 3; ++i) a.third[i] += w * b.third[i];
    for (int j = 0; j < kSourceDirections; ++j) a.toward[j] += w * b.toward[j];
}

bool similarDensity(double a, double b) { return a <= kPooledDensityRatio * b && b <= kPooledDensityRatio * a; }

}  // namespace

std::vector<SourceEstimate> pooledEstimates(const Medium &medium, const std::vector<openvdb::Coord> &voxels,
                                            const std::vector<SourceEstimate> &estimates) {
    openvdb::Int32Tree indexTree(-1);
    {
        openvdb::tree::ValueAccessor<openvdb::Int32Tree> index(indexTree);
        for (std::size_t v = 0; v < voxels.size(); ++v) index.setValue(voxels[v], std::int32_t(v));
    }
    std::vector<SourceEstimate> out(estimates);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 64), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(indexTree);
        Medium::Accessor density = medium.accessor();
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
            const double own = density.getValue(voxels[v]);
            SourceEstimate sum = estimates[v];
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const openvdb::Coord c = voxels[v].offsetBy(dx, dy, dz);
                        const std::int32_t n = index.getValue(c);
                        if (n >= 0 && std::size_t(n) != v && similarDensity(density.getValue(c), own))
                            addScaled(sum, estimates[std::size_t(n)], 1.0);
                    }
            const double pooledMean = channelMean(sum.l0), ownMean = channelMean(estimates[v].l0);
            if (!(pooledMean > 0.0)) continue;  // no light to take the shape of: its own
            SourceEstimate &shaped = out[v] = SourceEstimate{};
            addScaled(shaped, sum, ownMean / pooledMean);
            shaped.l0 = estimates[v].l0, shaped.steps = estimates[v].steps;
        }
    });
    return out;
}

}  // namespace firn
