#include "firn/transport/edge_lobe.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr int kDirections = 256, kLobeSteps = 19;

// Directions spread evenly over the sphere (a Fibonacci lattice): equal solid angle each.
const std::array<glm::dvec3, kDirections> &sphereDirections() {
    static const auto directions = [] {
        std::array<glm::dvec3, kDirections> out;
        const double golden = kPi * (3.0 - std::sqrt(5.0));
        for (int i = 0; i < kDirections; ++i) {
            const double z = 1.0 - (2.0 * i + 1.0) / kDirections, r = std::sqrt(1.0 - z * z);
            out[i] = glm::dvec3(r * std::cos(golden * i), r * std::sin(golden * i), z);
        }
        return out;
    }();
    return directions;
}

}  // namespace

SourceLobe edgeLobe(const std::vector<FaceExit> &faces) {
    struct Node {
        glm::dvec3 w;
        double T, weight;  // the mix seen towards w; the faces' projected area seen from w
    };
    std::vector<Node> nodes;
    nodes.reserve(kDirections);
    double flux = 0.0, most = 0.0, seen = 0.0;  // flux: the linear forms', negative parts included (their energy)
    glm::dvec3 moment(0.0);
    for (const glm::dvec3 &w : sphereDirections()) {
        double weight = 0.0, mixed = 0.0;
        for (const FaceExit &face : faces) {
            const double c = glm::dot(face.normal, w);
            if (c <= 0.0) continue;
            const double L = face.e0 + glm::dot(face.e1, w);
            weight += c, mixed += c * std::max(0.0, L), flux += c * L;
        }
        if (weight <= 0.0) continue;
        nodes.push_back({w, mixed / weight, weight});
        most = std::max(most, mixed / weight), seen += weight, moment += mixed * w;
    }
    if (flux <= 0.0 || most <= 0.0) return {};
    glm::dvec3 axis = moment;
    for (const FaceExit &face : faces) axis += 1e-9 * most * face.normal;  // where T is even: out of the edge
    axis = glm::normalize(axis);
    // Relative error, its denominator floored (at a tenth of the mean) where T nears zero.
    const double floor2 = 0.01 * (flux / seen) * (flux / seen);
    SourceLobe best;
    double least = std::numeric_limits<double>::infinity();
    for (int step = 0; step <= kLobeSteps; ++step) {
        const double k = kMaxLobeAnisotropy * step / kLobeSteps;
        const glm::dvec3 l1 = 3.0 * k * axis;  // of the lobe of mean 1
        double lobeFlux = 0.0;
        for (const Node &n : nodes) lobeFlux += n.weight * lobeRadiance(1.0, l1, n.w);
        const double l0 = flux / lobeFlux;
        if (l0 > most) continue;
        double error = 0.0;
        for (const Node &n : nodes) {
            const double r = l0 * lobeRadiance(1.0, l1, n.w) - n.T;
            error += n.weight * r * r / (n.T * n.T + floor2);
        }
        if (error < least) least = error, best = {l0, l1 * l0};
    }
    return best;
}

}  // namespace firn
