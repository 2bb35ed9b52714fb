#include "firn/transport/ramp_lobe.h"

#include <cmath>
#include <functional>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>
#include <gtest/gtest.h>

#include "firn/util/sampling.h"

namespace firn {

namespace {

// Midpoint quadrature of f over the hemisphere around n: the integral of f, and of f w.
glm::dvec4 overHemisphere(const glm::dvec3 &n, const std::function<double(const glm::dvec3 &)> &f, int steps = 200) {
    const Frame frame(n);
    glm::dvec4 out(0.0);
    for (int i = 0; i < steps; ++i)
        for (int j = 0; j < steps; ++j) {
            const double mu = (i + 0.5) / steps, phi = 2.0 * kPi * (j + 0.5) / steps, s = std::sqrt(1.0 - mu * mu);
            const glm::dvec3 w = frame.toWorld(s * std::cos(phi), s * std::sin(phi), mu);
            const double v = f(w) * 2.0 * kPi / (double(steps) * steps);
            out += glm::dvec4(v, v * w);
        }
    return out;
}

// The oracle: the in-scatter towards w of a face's lobe (l0, l1) leaving through its outward hemisphere n,
// J(w) = albedo integral over n . w' > 0 of lobeRadiance(l0, l1, w') HG(g, w . w') dw' (numerical).
double inScatter(double l0, const glm::dvec3 &l1, const glm::dvec3 &n, double g, double albedo, const glm::dvec3 &w,
                 int steps = 200) {
    return albedo * overHemisphere(n, [&](const glm::dvec3 &v) {
               return lobeRadiance(l0, l1, v) * henyeyGreenstein(glm::dot(w, v), g);
           }, steps).x;
}

// The direction at cosine c from n, turned from it towards `towards` (not along n).
glm::dvec3 at(const glm::dvec3 &n, const glm::dvec3 &towards, double c) {
    const glm::dvec3 side = glm::normalize(towards - glm::dot(towards, n) * n);
    return c * n + std::sqrt(1.0 - c * c) * side;
}

}  // namespace

TEST(RampLobe, KeepsTheFacesLightScatteredOnce) {
    // Mean: albedo times the face lobe's mean over its hemisphere (HG keeps the light); first moment along g times the
    // face's over it (HG's Legendre terms multiply), for a face lobe tilted off its normal.
    const double l0 = 1.3, g = 0.7, albedo = 0.9;
    const glm::dvec3 n = glm::normalize(glm::dvec3(0.2, -0.3, 1.0));
    const glm::dvec3 l1 = 3.0 * 0.3 * l0 * glm::normalize(glm::dvec3(1.0, 0.4, 1.2));  // k 0.3, 40 degrees off n
    const glm::dvec4 face = overHemisphere(n, [&](const glm::dvec3 &v) { return lobeRadiance(l0, l1, v); }, 400);
    const SourceLobe ramp = rampLobe(l0, l1, n, g, albedo);
    EXPECT_NEAR(ramp.l0, albedo * face.x / (4.0 * kPi), 5e-3 * ramp.l0);
    const glm::dvec3 moment(face.y, face.z, face.w);
    EXPECT_GT(glm::dot(glm::normalize(ramp.l1), glm::normalize(moment)), std::cos(2.0 * kPi / 180.0));
    EXPECT_EQ(rampLobe(0.0, l1, n, g, albedo).l0, 0.0);  // no light
}

TEST(RampLobe, ShowsNoBackTailBeyondTheInScatter) {
    // A flat face's escape-shaped lobe (k 0.24 about its normal: exitLobe's fit) in snow of g 0.7: the air across it
    // scatters little back towards the snow (docs/benchmarks.md, box-foot-b: J 0.25 of the mean exit radiance at
    // n . w -0.71, the face's lobe 0.57). The stored lobe is nearer J than the face's own lobe behind, grazing and along n,
    // and its squared error over the sphere is at most that of any other k with J's mean (it is the least-squares
    // fit, within the table's interpolation).
    const double l0 = 1.0, g = 0.7;
    const glm::dvec3 n(0.0, 0.0, 1.0), l1 = 3.0 * 0.24 * l0 * n;
    const SourceLobe ramp = rampLobe(l0, l1, n, g, 1.0);
    for (double c : {-1.0, -0.71, -0.3, 0.0, 1.0}) {  // at c 0.5 J lies between them (J 1.10, face 1.27, fit 0.88)
        const glm::dvec3 w = at(n, glm::dvec3(1.0, 0.0, 0.0), c);
        const double J = inScatter(l0, l1, n, g, 1.0, w);
        EXPECT_LT(std::abs(lobeRadiance(ramp.l0, ramp.l1, w) - J), std::abs(lobeRadiance(l0, l1, w) - J)) << c;
    }
    const glm::dvec3 w = at(n, glm::dvec3(1.0, 0.0, 0.0), -0.71);
    EXPECT_LT(lobeRadiance(ramp.l0, ramp.l1, w), 0.65 * lobeRadiance(l0, l1, w));  // the back tail: 0.33 against 0.57
    // Squared error over the sphere (midpoint nodes in mu; the lobes are symmetric about n).
    std::vector<std::pair<double, double>> nodes;  // cos to n, J
    for (int i = 0; i < 40; ++i) {
        const double c = -1.0 + (i + 0.5) / 20.0;
        nodes.push_back({c, inScatter(l0, l1, n, g, 1.0, at(n, glm::dvec3(1.0, 0.0, 0.0), c), 100)});
    }
    const auto error = [&](double mean, const glm::dvec3 &moment) {
        double sum = 0.0;
        for (const auto &[c, J] : nodes) {
            const double r = lobeRadiance(mean, moment, at(n, glm::dvec3(1.0, 0.0, 0.0), c)) - J;
            sum += r * r;
        }
        return sum;
    };
    const double fitted = error(ramp.l0, ramp.l1);
    EXPECT_LT(fitted, 0.25 * error(l0, l1));
    for (double k = 0.0; k < 0.95; k += 0.05) EXPECT_LE(fitted, 1.02 * error(ramp.l0, 3.0 * k * ramp.l0 * n)) << k;
}

}  // namespace firn
