#include "firn/transport/incident_light.h"

#include <cmath>

#include <gtest/gtest.h>

namespace firn {
namespace {

// Henyey-Greenstein's share of singly scattered light within alpha of the forward direction (its exact
// cumulative distribution): 1 - (1 - g^2) / (2 g) (1 / sqrt(1 + g^2 - 2 g cos alpha) - 1 / (1 + g)).
double henyeyGreensteinWithin(double alpha, double g) {
    return 1.0 - (1.0 - g * g) / (2.0 * g) * (1.0 / std::sqrt(1.0 + g * g - 2.0 * g * std::cos(alpha)) - 1.0 / (1.0 + g));
}

TEST(ForwardShare, ThinPieceSendsWhatHenyeyGreensteinScattersTowardsThePoint) {
    // Optically thin: one scattering; a disc of radius r seen from d on its axis at half-angle atan(r / d) takes, by
    // reciprocity, the phase function's share within that angle (the small-angle form: within 0.05 up to 0.8 rad).
    for (double g : {0.7, 0.845, 0.9})
        for (double alpha : {0.05, 0.1, 0.2, 0.4, 0.8}) {
            const double d = 0.1, r = d * std::tan(alpha);
            EXPECT_NEAR(forwardShare(r, d, 1e-9, g), henyeyGreensteinWithin(alpha, g), 0.05) << "g " << g << " alpha " << alpha;
        }
}

TEST(ForwardShare, AllRightBehindTheSpreadingConeFurtherOff) {
    EXPECT_DOUBLE_EQ(forwardShare(0.006, 0.0, 3.0, 0.845), 1.0);
    EXPECT_GT(forwardShare(0.006, 0.001, 3.0, 0.845), 0.9);
    // Deeper pieces scatter more times on the way through: a wider cone, a smaller share at the same distance.
    EXPECT_LT(forwardShare(0.006, 0.05, 5.0, 0.845), forwardShare(0.006, 0.05, 1.0, 0.845));
    EXPECT_NEAR(forwardConeWidth(5.0, 0.845) / forwardConeWidth(1e-9, 0.845), 5.0 / (1.0 - std::exp(-5.0)), 1e-9);
}

}  // namespace
}  // namespace firn
