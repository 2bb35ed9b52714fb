#include "firn/structure/sub_balls.h"

#include <algorithm>
#include <string>

#include "firn/util/error.h"

namespace firn {

namespace {
// Cells three grain radii wide: the grains fill about 15 % of the shallow snow, sparse enough to show as grains
// and dense enough that most lines of sight meet one within a few cells.
constexpr double kCellsPerRadius = 3.0;
}  // namespace

void SubBallSettings::validate() const {
    if (!(radius > 0.0 && radius < 0.1))
        throw InvalidArgument("sub-ball radius must be in (0, 0.1) m, got " + std::to_string(radius));
    if (!(variation >= 0.0 && variation < 1.0))
        throw InvalidArgument("sub-ball size variation must be in [0, 1), got " + std::to_string(variation));
    if (!(depth > 0.0)) throw InvalidArgument("sub-ball depth must be positive (optical depths)");
    if (!(strength >= 0.0 && strength <= 1.0))
        throw InvalidArgument("sub-ball strength must be in [0, 1], got " + std::to_string(strength));
}

double SubBallPattern::densityFactor(double distance, double radius, double depth) const {
    const double q = std::max(0.0, 1.0 - (distance / radius) * (distance / radius));
    const double w = std::clamp((fadeEnd - depth) / (fadeEnd - fadeStart), 0.0, 1.0);
    return 1.0 + strength * w * (q * q * q / meanKernel - 1.0);
}

SubBallPattern subBallPattern(const SubBallSettings &settings, double sigmaT) {
    settings.validate();
    if (!(sigmaT > 0.0)) throw InvalidArgument("sub-balls need snow with a positive extinction");
    SubBallPattern pattern;
    pattern.cellSize = kCellsPerRadius * settings.radius;
    pattern.balls = {1.0 / kCellsPerRadius, settings.variation};
    pattern.meanKernel = cellBallMeans(pattern.balls).kernel;
    pattern.fadeEnd = settings.depth / sigmaT;
    pattern.fadeStart = 0.5 * pattern.fadeEnd;
    pattern.strength = settings.strength;
    return pattern;
}

}  // namespace firn
