#include "firn/structure/cell_balls.h"

#include <cmath>
#include <limits>
#include <string>

#include "firn/util/error.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

void CellBalls::validate() const {
    if (!(radius > 0.0 && radius <= 1.0))
        throw InvalidArgument("ball radius must be in (0, 1] cells, got " + std::to_string(radius));
    if (!(variation >= 0.0 && variation < 1.0))
        throw InvalidArgument("ball size variation must be in [0, 1), got " + std::to_string(variation));
}

namespace {

// The ball of the nearest centre to a point in cell (0, 0, 0): its distance and its radius (cells).
struct NearestBall {
    double distance = std::numeric_limits<double>::infinity();
    double radius = 0.0;
};

NearestBall nearestBall(const CellBalls &balls, Rng &rng) {
    const double x[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
    NearestBall nearest;
    for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
            for (int k = -1; k <= 1; ++k) {
                const double dx = i + rng.uniform() - x[0], dy = j + rng.uniform() - x[1], dz = k + rng.uniform() - x[2];
                const double u = rng.uniform();
                const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
                if (d < nearest.distance) nearest = {d, balls.radius * (1.0 + balls.variation * (2.0 * u - 1.0))};
            }
    return nearest;
}

}  // namespace

CellBallMeans cellBallMeans(const CellBalls &balls, std::uint64_t samples, std::uint64_t seed) {
    balls.validate();
    if (samples == 0) throw InvalidArgument("cellBallMeans needs at least one sample");
    double inside = 0.0, kernel = 0.0;
    for (std::uint64_t n = 0; n < samples; ++n) {
        Rng rng(seed, n);
        const NearestBall ball = nearestBall(balls, rng);
        if (ball.distance >= ball.radius) continue;
        const double q = 1.0 - (ball.distance / ball.radius) * (ball.distance / ball.radius);
        inside += 1.0;
        kernel += q * q * q;
    }
    return {inside / double(samples), kernel / double(samples)};
}

CellBallMeans cellBallMeansWithoutOverlap(const CellBalls &balls) {
    balls.validate();
    // E[(1 + v w)^3] = 1 + v^2 for w uniform in [-1, 1]; the integral of (1 - t^2)^3 t^2 over [0, 1] is 16/315.
    const double meanCube = balls.radius * balls.radius * balls.radius * (1.0 + balls.variation * balls.variation);
    return {4.0 / 3.0 * kPi * meanCube, 64.0 * kPi / 315.0 * meanCube};
}

}  // namespace firn
