#include "firn/transport/slab.h"

#include <array>
#include <cmath>

#include "firn/util/error.h"
#include "firn/util/openvdb_library.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {
constexpr double kMaxSlabVoxels = 16e6;
}  // namespace

openvdb::FloatGrid::Ptr makeSlabDensity(double voxelSize, int width, int layers, float density) {
    initializeOpenVdb();
    if (!(voxelSize > 0.0) || !std::isfinite(voxelSize) || width < 1 || layers < 1 || !(density > 0.0f) ||
        !std::isfinite(density))
        throw InvalidArgument("slab: voxel size, width, layers and density must be positive and finite");
    // A test geometry: far more voxels than any test needs is a mistake, refused before filling.
    if (double(width) * width * layers > kMaxSlabVoxels)
        throw BudgetExceeded("slab: " + std::to_string(width) + " x " + std::to_string(width) + " x " +
                             std::to_string(layers) + " voxels is over the test slab's budget of 16 million");
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    auto transform = openvdb::math::Transform::createLinearTransform(voxelSize);
    // Voxel (i, j, k) centred at ((i - (width - 1) / 2) h, (j - (width - 1) / 2) h, (k + 1/2) h).
    transform->postTranslate(openvdb::Vec3d(-0.5 * (width - 1) * voxelSize, -0.5 * (width - 1) * voxelSize, 0.5 * voxelSize));
    grid->setTransform(transform);
    grid->tree().fill(openvdb::CoordBBox(openvdb::Coord(0, 0, -layers), openvdb::Coord(width - 1, width - 1, -1)),
                      density, true);
    grid->tree().voxelizeActiveTiles();
    return grid;
}

double renderedExitance(const Scene &scene, const BakedGrids &baked, const glm::dvec3 &point,
                        const glm::dvec3 &normal, int channel, int muNodes, int phiNodes) {
    // Gauss-Legendre nodes on [-1, 1] by Newton iteration on P_n.
    double sum = 0.0;
    for (int m = 0; m < muNodes; ++m) {
        double x = std::cos(kPi * (m + 0.75) / (muNodes + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = x;
            for (int k = 2; k <= muNodes; ++k) {
                const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
                p0 = p1, p1 = p2;
            }
            dp = muNodes * (x * p1 - p0) / (x * x - 1.0);
            const double dx = p1 / dp;
            x -= dx;
            if (std::abs(dx) < 1e-15) break;
        }
        const double weight = 2.0 / ((1.0 - x * x) * dp * dp) * 0.5;  // mapped to mu in [0, 1]
        const double mu = 0.5 * (x + 1.0);
        for (int p = 0; p < phiNodes; ++p) {
            const glm::dvec3 w = directionAround(normal, mu, 2.0 * kPi * (p + 0.5) / phiNodes);
            const Rgb L = renderBaked(scene, baked, Ray{point + 10.0 * scene.medium->voxelSize() * w / std::max(mu, 0.05), -w});
            sum += weight * (2.0 * kPi / phiNodes) * mu * L[channel];
        }
    }
    return sum;
}

}  // namespace firn
