#include "firn/transport/edge_lobe.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/util/sampling.h"

namespace firn {

namespace {

// The light leaving through the faces, of radiance L(w) seen through each face by its cosine: the sum over
// faces of the integral of max(0, n . w) L(w), by midpoint quadrature over the sphere.
template <typename Radiance>
double fluxThroughFaces(const std::vector<FaceExit> &faces, const Radiance &L, int n = 300) {
    double out = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double mu = -1.0 + 2.0 * (i + 0.5) / n, phi = 2.0 * kPi * (j + 0.5) / n, s = std::sqrt(1.0 - mu * mu);
            const glm::dvec3 w(s * std::cos(phi), s * std::sin(phi), mu);
            for (const FaceExit &face : faces)
                out += std::max(0.0, glm::dot(face.normal, w)) * L(w, face) * 4.0 * kPi / (double(n) * n);
        }
    return out;
}

}  // namespace

TEST(EdgeLobe, KeepsTheLightLeavingThroughTheFaces) {
    // An edge between a sunlit top (radiance 0.3 + 0.1 mu) and a darker side (0.05): the lobe carries the light
    // the two faces let out, within the quadrature of its 256 directions.
    const std::vector<FaceExit> faces{{{0.0, 0.0, 1.0}, 0.3, {0.0, 0.0, 0.1}}, {{-1.0, 0.0, 0.0}, 0.05, {0.0, 0.0, 0.0}}};
    const SourceLobe lobe = edgeLobe(faces);
    const double exact =
        fluxThroughFaces(faces, [](const glm::dvec3 &w, const FaceExit &f) { return f.e0 + glm::dot(f.e1, w); });
    const double stored =
        fluxThroughFaces(faces, [&](const glm::dvec3 &w, const FaceExit &) { return lobeRadiance(lobe.l0, lobe.l1, w); });
    EXPECT_NEAR(stored, exact, 0.03 * exact);
}

TEST(EdgeLobe, ShowsTheLitFaceBrighterThanTheDarkOne) {
    // Seen straight down (only the top visible) against straight from the side (only the side): a lobe about
    // one smooth patch's diagonal normal would show both alike; this one leans towards the lit face.
    const std::vector<FaceExit> faces{{{0.0, 0.0, 1.0}, 0.3, {0.0, 0.0, 0.0}}, {{-1.0, 0.0, 0.0}, 0.03, {0.0, 0.0, 0.0}}};
    const SourceLobe lobe = edgeLobe(faces);
    const double top = lobeRadiance(lobe.l0, lobe.l1, {0.0, 0.0, 1.0}), side = lobeRadiance(lobe.l0, lobe.l1, {-1.0, 0.0, 0.0});
    EXPECT_GT(top, 3.0 * side);
    EXPECT_LE(lobe.l0, 0.3);  // never above the brightest radiance the faces show
}

TEST(EdgeLobe, NothingWhereNoLightLeaves) {
    const SourceLobe lobe = edgeLobe({{{0.0, 0.0, 1.0}, 0.0, {0.0, 0.0, 0.0}}, {{1.0, 0.0, 0.0}, 0.0, {0.0, 0.0, 0.0}}});
    EXPECT_EQ(lobe.l0, 0.0);
    EXPECT_EQ(glm::length(lobe.l1), 0.0);
}

// A lit top (mean radiance 0.3) beside a dark side (0.1): each face's mean moves by kappa of the difference, what
// the top loses the side gains, and never past the two faces' mean (kappa <= 1/2).
TEST(EdgeLobe, RelaxedFacesMeetAtMostAtTheirMean) {
    for (const double kappa : {0.5, 0.2, 0.0}) {
        std::vector<FaceExit> faces{{{0.0, 0.0, 1.0}, 0.3, {0.0, 0.0, 0.0}}, {{-1.0, 0.0, 0.0}, 0.1, {0.0, 0.0, 0.0}}};
        relaxTowardsNeighbours(faces, kappa);
        EXPECT_NEAR(faces[0].e0, 0.3 - 0.2 * kappa, 1e-9) << kappa;
        EXPECT_NEAR(faces[1].e0, 0.1 + 0.2 * kappa, 1e-9) << kappa;
        EXPECT_GE(faces[0].e0, faces[1].e0 - 1e-12) << kappa;
    }
}

// The dipole's share from beyond the edge, against its closed form where nothing is absorbed (the line-integrated
// kernel 2 z / (u^2 + z^2): 1/2 - [atan(1/z) - z/2 ln(1 + 1/z^2)] / pi per source) and, absorbing, against the plane's
// integral summed directly (the kernel along the edge summed over y, then across it over u > x, x over the voxel):
// 1/2 for a voxel thin against the transport mean free path, less as the voxel thickens or the snow absorbs.
TEST(EdgeLobe, EdgeExitShareIsTheDipolesSpreadBeyondTheEdge) {
    for (const double paths : {0.5, 2.43, 4.51, 20.0}) {
        double closed = 0.0;
        for (const double z : {1.0 / paths, 7.0 / 3.0 / paths})
            closed += 0.5 * (0.5 - (std::atan(1.0 / z) - 0.5 * z * std::log(1.0 + 1.0 / (z * z))) / kPi);
        EXPECT_NEAR(edgeExitShare(0.0, paths), closed, 1e-4) << paths;
    }
    const double s = 0.45, paths = 4.51, step = 0.02;  // the tests' slab: sigma_t h 15, omega 0.999, g 0.7
    double beyond = 0.0, leaving = 0.0;
    for (const double z : {1.0 / paths, 7.0 / 3.0 / paths}) {
        // along[n]: the kernel at u = (n + 1/2) step summed over y (over the whole plane it sums to 2 pi exp(-s z)).
        std::vector<double> along(1500);
        for (std::size_t n = 0; n < along.size(); ++n)
            for (double y = 0.5 * step; y < 30.0; y += step) {
                const double u = (double(n) + 0.5) * step, rho = std::sqrt(u * u + y * y + z * z);
                along[n] += 2.0 * step * z * (1.0 + s * rho) * std::exp(-s * rho) / (rho * rho * rho);
            }
        for (std::size_t n = 0; n < along.size(); ++n)  // min(u, 1): the mean over x in [0, 1] of [u > x]
            beyond += along[n] * step * std::min((double(n) + 0.5) * step, 1.0) / (2.0 * kPi);
        leaving += std::exp(-s * z);
    }
    EXPECT_NEAR(edgeExitShare(s, paths), beyond / leaving, 0.003);
    EXPECT_LT(edgeExitShare(s, paths), edgeExitShare(0.0, paths));
    EXPECT_NEAR(edgeExitShare(0.0, 1e-3), 0.5, 1e-3);
}

// A lit top's grazing return beside a shadowed side (the edge voxel's two faces, half its area each: the top, which
// sends all of the peak, at twice the voxel's radiance): a camera along the peak's axis, 5 degrees above the top, sees
// the voxel through the top's projected area sin 5 and the side's cos 5, so the voxel's one value shows
// 2 sin 5 / (sin 5 + cos 5) of its stored peak there; a peak straight up shows the top's own radiance, one that leaves
// through both faces alike the voxel's, and one that no face faces is kept whole.
TEST(EdgeLobe, PeakSeenThroughTheFaceItLeaves) {
    const std::vector<glm::dvec3> normals{{0.0, 0.0, 1.0}, {-1.0, 0.0, 0.0}};
    const double e = 5.0 * kPi / 180.0;
    const glm::dvec3 grazing(-std::cos(e), 0.0, std::sin(e));
    EXPECT_NEAR(peakSeenThroughFaces(normals, {2.0, 0.0}, grazing), 2.0 * std::sin(e) / (std::sin(e) + std::cos(e)),
                1e-12);
    EXPECT_NEAR(peakSeenThroughFaces(normals, {2.0, 0.0}, {0.0, 0.0, 1.0}), 2.0, 1e-12);
    EXPECT_NEAR(peakSeenThroughFaces(normals, {1.0, 1.0}, grazing), 1.0, 1e-12);
    EXPECT_NEAR(peakSeenThroughFaces(normals, {2.0, 0.0}, glm::normalize(glm::dvec3(1.0, 0.0, -0.2))), 1.0, 1e-12);
}

}  // namespace firn
