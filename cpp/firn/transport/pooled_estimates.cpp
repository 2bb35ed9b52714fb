#include "firn/transport/pooled_estimates.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/traced_source.h"
#include "firn/util/color.h"

namespace firn {

namespace {

bool similarDensity(double a, double b) { return a <= kPooledDensityRatio * b && b <= kPooledDensityRatio * a; }

}  // namespace

std::vector<SourceEstimate> pooledEstimates(const Medium &medium, const openvdb::Int32Tree &indexTree,
                                            const std::vector<openvdb::Coord> &voxels,
                                            const std::vector<SourceEstimate> &estimates) {
    std::vector<SourceEstimate> out(estimates);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 64), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(indexTree);
        Medium::Accessor density = medium.accessor();
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
            // Only voxels fitted by direction hold a `toward`; an unfitted neighbour's l0 would dilute the sum.
            if (!fittedByDirection(medium, density, voxels[v])) continue;
            const double own = density.getValue(voxels[v]);
            double l0 = channelMean(estimates[v].l0);
            std::array<double, kSourceDirections> toward = estimates[v].toward;
            int neighbours = 0;
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const openvdb::Coord c = voxels[v].offsetBy(dx, dy, dz);
                        const std::int32_t n = index.getValue(c);
                        if (n < 0 || std::size_t(n) == v || !similarDensity(density.getValue(c), own) ||
                            !fittedByDirection(medium, density, c))
                            continue;
                        const SourceEstimate &other = estimates[std::size_t(n)];
                        l0 += channelMean(other.l0), ++neighbours;
                        for (int j = 0; j < kSourceDirections; ++j) toward[j] += other.toward[j];
                    }
            if (neighbours < kMinPooledNeighbours || !(l0 > 0.0)) continue;  // its own
            const double scale = channelMean(estimates[v].l0) / l0;
            for (int j = 0; j < kSourceDirections; ++j) out[v].toward[j] = scale * toward[j];
        }
    });
    return out;
}

}  // namespace firn
