// The sky rays of a surface patch (SkyRays, incident_light.h): any count, each ray in a cell of its own.

#include "firn/transport/incident_light.h"

#include <cmath>
#include <set>
#include <utility>

#include <gtest/gtest.h>

#include "firn/util/sampling.h"

namespace firn {

// Around the normal +z (Frame's t = +x, b = +y) a cosine-weighted ray's coordinates are u1 = 1 - cos^2(theta) and
// u2 = azimuth / (2 pi) (sampleCosineHemisphere). With rows r the largest divisor of n not above sqrt(n) and n / r
// columns, a patch's n rays fill the r x (n / r) grid over (u1, u2) once each: 6 rays 2 x 3, 7 rays 1 x 7, and the
// square counts FINAL and REFERENCE asked before (9, 64) their k-th ray in cell (k / side, k % side) as ever.
TEST(SkyRays, AnyCountFillsItsGridOnceEach) {
    const glm::dvec3 up(0.0, 0.0, 1.0);
    for (int n = 1; n <= SkyRays::kMaxRays; ++n) {
        const SkyRays rays(n);
        ASSERT_EQ(rays.count(), n);
        int rows = 1;
        for (int r = 1; r * r <= n; ++r)
            if (n % r == 0) rows = r;
        const int columns = n / rows;
        for (std::uint64_t stream = 0; stream < 20; ++stream) {
            std::set<std::pair<int, int>> cells;
            for (int k = 0; k < n; ++k) {
                const glm::dvec3 w = rays.direction(up, k, 7, stream);
                const double u1 = 1.0 - w.z * w.z;
                double u2 = std::atan2(w.y, w.x) / (2.0 * kPi);
                if (u2 < 0.0) u2 += 1.0;
                const std::pair<int, int> cell(int(u1 * rows), int(u2 * columns));
                EXPECT_EQ(cell, std::make_pair(k / columns, k % columns)) << n << " rays, ray " << k;
                cells.insert(cell);
            }
            EXPECT_EQ(int(cells.size()), n);
        }
    }
    EXPECT_EQ(SkyRays(0).count(), 1);
    EXPECT_EQ(SkyRays(100).count(), SkyRays::kMaxRays);
}

}  // namespace firn
