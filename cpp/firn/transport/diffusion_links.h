#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "firn/transport/voxel_links.h"
#include "firn/util/unwritten_vector.h"

namespace firn {

// Finite volumes with exponential fitting: every link between two unknowns, and between an unknown and
// a boundary, is treated as the exact one-dimensional diffusion problem -phi'' + beta^2 phi = 0 in the
// resistance coordinate R (dR = 3 sigma_tr dz), so voxels many diffusion lengths thick stay exact.

// A link between two unknowns R apart: conductance, and the absorption it lends each end.
struct Link {
    double conductance, halfMass;  // per unit face area
};
// sinh(x) / x and tanh(x) / x, by series where x is small (snow: x ~ 0.1 per voxel), where they are
// exact to double precision and cost no exponentials.
inline double sinhOverX(double x) {
    const double x2 = x * x;
    return x < 0.3 ? 1.0 + x2 / 6.0 * (1.0 + x2 / 20.0 * (1.0 + x2 / 42.0 * (1.0 + x2 / 72.0))) : std::sinh(x) / x;
}
inline double tanhOverX(double x) {
    const double x2 = x * x;
    return x < 0.1 ? 1.0 - x2 / 3.0 * (1.0 - 0.4 * x2 * (1.0 - 17.0 / 42.0 * x2)) : std::tanh(x) / x;
}

inline Link interiorLink(double beta, double R) {
    const double x = beta * R;
    return {1.0 / (R * sinhOverX(x)), 0.5 * beta * x * tanhOverX(0.5 * x)};
}

// The interior links of a run of unknowns [begin, end), each computed once: a link between two unknowns of the run
// is the same from either end (its resistance, 3 sigma_tr over the h between their nodes, sums their sigma_tr in
// either order), so the run's links along +x, +y and +z are computed first and its links along -x, -y and -z read
// them where the neighbour lies in the run (the assembly's divisions were most of its time). The values are
// interiorLink's, bit for bit. `link`: per unknown its neighbours (voxel_links.h); `density` kg/m^3;
// sigma_tr = sigmaTrPerDensity * density (1/m); h the voxel (m).
class SharedLinks {
  public:
    SharedLinks(const VoxelLinks &link, const UnwrittenVector<float> &density, double sigmaTrPerDensity, double beta,
                double h, std::size_t begin, std::size_t end)
        : link_(link), density_(density), sigmaTrPerDensity_(sigmaTrPerDensity), beta_(beta), h_(h), begin_(begin),
          end_(end), upper_(3 * (end - begin)) {
        for (std::size_t i = begin; i != end; ++i)
            for (int axis = 0; axis < 3; ++axis) {
                const std::int32_t j = link[i][2 * axis + 1];
                if (j >= 0) upper_[3 * (i - begin) + axis] = computed(i, std::size_t(j));
            }
    }
    // The link through face f (0..5: -x, +x, -y, +y, -z, +z) of unknown i of the run, whose neighbour there is an
    // unknown.
    Link at(std::size_t i, int f) const {
        const std::size_t j = std::size_t(link_[i][f]);
        if (f & 1) return upper_[3 * (i - begin_) + f / 2];
        if (j >= begin_ && j < end_) return upper_[3 * (j - begin_) + f / 2];  // i is j's upper neighbour
        return computed(i, j);
    }

  private:
    Link computed(std::size_t i, std::size_t j) const {
        return interiorLink(beta_, 1.5 * h_ * (sigmaTrPerDensity_ * density_[i] + sigmaTrPerDensity_ * density_[j]));
    }
    const VoxelLinks &link_;
    const UnwrittenVector<float> &density_;
    double sigmaTrPerDensity_, beta_, h_;
    std::size_t begin_, end_;
    std::vector<Link> upper_;  // per unknown of the run, its +x, +y, +z links (where a neighbour is)
};

}  // namespace firn
