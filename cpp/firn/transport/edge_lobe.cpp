#include "firn/transport/edge_lobe.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr int kDirections = 128, kCoarseSteps = 10, kFineSteps = 4;

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
        double cos, T, weight;  // to the lobe's axis; the mix seen towards w; the faces' projected area seen from w
    };
    std::array<Node, kDirections> nodes;
    std::array<glm::dvec3, kDirections> directions;
    int count = 0;
    double flux = 0.0, most = 0.0, seen = 0.0;  // flux: the linear forms', negative parts included (their energy)
    glm::dvec3 moment(0.0);
    for (const glm::dvec3 &w : sphereDirections()) {
        double mixed = 0.0;
        const double weight = projectedArea(faces, w, [&](std::size_t f, double c) {
            const double L = faces[f].e0 + glm::dot(faces[f].e1, w);
            mixed += c * std::max(0.0, L), flux += c * L;
        });
        if (weight <= 0.0) continue;
        directions[count] = w, nodes[count++] = {0.0, mixed / weight, weight};
        most = std::max(most, mixed / weight), seen += weight, moment += mixed * w;
    }
    if (flux <= 0.0 || most <= 0.0) return {};
    glm::dvec3 axis = moment;
    for (const FaceExit &face : faces) axis += 1e-9 * most * face.normal;  // where T is even: out of the edge
    axis = glm::normalize(axis);
    for (int n = 0; n < count; ++n) nodes[n].cos = glm::dot(axis, directions[n]);
    // Relative error, its denominator floored (at a tenth of the mean) where T nears zero. For the lobe of mean 1,
    // L_k, scaled to keep the flux (l0 = flux / sum w L_k), the error is l0^2 sum w L_k^2 / D - 2 l0 sum w L_k T / D
    // + sum w T^2 / D, D = T^2 + floor^2: one pass over the nodes per k.
    const double floor2 = 0.01 * (flux / seen) * (flux / seen);
    auto fit = [&](double k) {
        double lobeFlux = 0.0, lobe2 = 0.0, lobeT = 0.0, T2 = 0.0;
        for (int n = 0; n < count; ++n) {
            const Node &node = nodes[n];
            const double d = 1.0 + k * k - 2.0 * k * node.cos, L = (1.0 - k * k) / (d * std::sqrt(d));  // 4 pi HG
            const double w = node.weight / (node.T * node.T + floor2);
            lobeFlux += node.weight * L, lobe2 += w * L * L, lobeT += w * L * node.T, T2 += w * node.T * node.T;
        }
        const double l0 = flux / lobeFlux;
        return std::pair{l0 > most ? std::numeric_limits<double>::infinity() : l0 * l0 * lobe2 - 2.0 * l0 * lobeT + T2, l0};
    };
    // k on a coarse grid, then finer around the best.
    double bestK = 0.0, least = std::numeric_limits<double>::infinity(), l0 = 0.0;
    auto consider = [&](double k) {
        const auto [error, scale] = fit(k);
        if (error < least) least = error, bestK = k, l0 = scale;
    };
    const double coarse = kMaxLobeAnisotropy / kCoarseSteps;
    for (int step = 0; step <= kCoarseSteps; ++step) consider(coarse * step);
    const double around = bestK;
    for (int step = -kFineSteps; step <= kFineSteps; ++step)
        consider(std::clamp(around + coarse * step / (kFineSteps + 1), 0.0, kMaxLobeAnisotropy));
    return {l0, 3.0 * bestK * l0 * axis};
}

SourceLobe lobeBeyondFaces(const FaceLobes &faces) {
    const auto seenBeyond = [&](const glm::dvec3 &w) {  // every face faces w
        return std::all_of(faces.begin(), faces.end(), [&](const FaceLobe &f) { return glm::dot(f.normal, w) > 0.0; });
    };
    double light = 0.0;  // T summed over the directions (equal solid angles), and its first moment
    glm::dvec3 moment(0.0);
    for (const glm::dvec3 &w : sphereDirections()) {
        if (!seenBeyond(w)) continue;
        double mixed = 0.0;
        const double seen = projectedArea(faces, w, [&](std::size_t f, double c) {
            mixed += c * lobeRadiance(faces[f].l0, faces[f].l1, w);
        });
        light += mixed / seen, moment += mixed / seen * w;
    }
    if (!(light > 0.0)) return {};
    const double k = std::min(glm::length(moment) / light, kMaxLobeAnisotropy);
    const glm::dvec3 axis = glm::normalize(moment);
    double lobe = 0.0;  // the lobe of mean 1 summed over the same directions
    for (const glm::dvec3 &w : sphereDirections())
        if (seenBeyond(w)) {
            const double d = 1.0 + k * k - 2.0 * k * glm::dot(axis, w);
            lobe += (1.0 - k * k) / (d * std::sqrt(d));
        }
    const double l0 = light / lobe;
    return {l0, 3.0 * k * l0 * axis};
}

double peakSeenThroughFaces(const std::vector<glm::dvec3> &normals, const std::vector<double> &radiance,
                            const glm::dvec3 &axis) {
    double shown = 0.0;
    const double seen = projectedArea(normals, axis, [&](std::size_t f, double c) { shown += radiance[f] * c; });
    return seen > 0.0 ? shown / seen : 1.0;
}

namespace {

// Of light travelling at sin(beta) = rise out of a plane and scattered once by a Henyey-Greenstein phase function of
// asymmetry g, the share heading back through the plane: over the scattering angle's cosine m (HG's density),
// the azimuths phi with m rise + sqrt(1 - m^2) cos(phi) sqrt(1 - rise^2) < 0; 1/2 at rise 0 by symmetry.
double scatteredBackThroughPlane(double g, double rise) {
    constexpr int kSteps = 256;
    const double across = std::sqrt(std::max(0.0, 1.0 - rise * rise));
    double share = 0.0, all = 0.0;  // the rule's own sum of the density: a sharp peak's midpoints miss a little
    for (int k = 0; k < kSteps; ++k) {
        const double m = -1.0 + 2.0 * (k + 0.5) / kSteps, sine = std::sqrt(1.0 - m * m);
        const double density = 1.0 / std::pow(1.0 + g * g - 2.0 * g * m, 1.5);
        const double q = sine * across > 0.0 ? -m * rise / (sine * across) : (m * rise < 0.0 ? 2.0 : -2.0);
        share += density * (1.0 - std::acos(std::clamp(q, -1.0, 1.0)) / kPi), all += density;  // cos(phi) < q
    }
    return share / all;
}

}  // namespace

double skimmedThroughRamp(const std::vector<glm::dvec3> &normals, const glm::dvec3 &n, const glm::dvec3 &w,
                          double voxelOpticalDepth, double g) {
    const double mu = glm::dot(n, w);
    if (mu > 0.0) return 0.0;
    double lit = 0.0;  // the lit neighbouring faces' cosines
    for (const glm::dvec3 &a : normals)
        if (std::abs(glm::dot(a, n)) < 0.5) lit += std::max(0.0, glm::dot(a, w));
    if (!(lit > 0.0)) return 0.0;
    const double spread = std::max(-mu, 1e-12) * 2.0 / voxelOpticalDepth;  // 1 / a
    const double caught = 1.0 - std::sqrt(kPi * spread) * std::erf(0.5 / std::sqrt(spread));
    return 0.5 * lit * caught * scatteredBackThroughPlane(g, -mu);
}

void relaxTowardsNeighbours(std::vector<FaceExit> &faces, double voxelInDiffusionLengths) {
    for (const FaceExit &a : faces)
        for (const FaceExit &b : faces)
            if (glm::dot(a.normal, b.normal) < -0.5) return;  // no snow beneath a face: a lump's tip, a thin plate
    const double s = voxelInDiffusionLengths;  // kappa: the mean of exp(-x s) / 2 over x in [0, 1]; 1/2 as s -> 0
    const double kappa = s > 1e-6 ? 0.5 * -std::expm1(-s) / s : 0.5;
    std::vector<double> mean(faces.size());  // W/m^2/sr: e0 + 2/3 e1 . n, the exitance over pi
    for (std::size_t f = 0; f < faces.size(); ++f)
        mean[f] = faces[f].e0 + 2.0 / 3.0 * glm::dot(faces[f].e1, faces[f].normal);
    for (std::size_t f = 0; f < faces.size(); ++f) {
        if (!(mean[f] > 0.0)) continue;
        double relaxed = mean[f];
        for (std::size_t g = 0; g < faces.size(); ++g)
            if (std::abs(glm::dot(faces[f].normal, faces[g].normal)) < 0.5) relaxed += kappa * (mean[g] - mean[f]);
        const double scale = std::max(0.0, relaxed / mean[f]);
        faces[f].e0 *= scale, faces[f].e1 *= scale;
    }
}

}  // namespace firn
