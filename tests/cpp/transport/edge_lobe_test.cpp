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

// A lit top (mean radiance 0.3) beside a dark side (0.1): their exits meet at the shared edge at their mean and the
// difference relaxes across the voxel over the diffusion length, so each face's mean moves by
// kappa = (1 - exp(-s)) / (2 s) of the difference (s: the voxel in diffusion lengths), what the top loses the side
// gains, and never past the two faces' mean: in snow that absorbs nothing (s -> 0) they meet at it.
TEST(EdgeLobe, RelaxedFacesMeetAtMostAtTheirMean) {
    for (const double s : {1e-9, 0.45, 4.5}) {
        std::vector<FaceExit> faces{{{0.0, 0.0, 1.0}, 0.3, {0.0, 0.0, 0.0}}, {{-1.0, 0.0, 0.0}, 0.1, {0.0, 0.0, 0.0}}};
        relaxTowardsNeighbours(faces, s);
        const double kappa = s < 1e-6 ? 0.5 : (1.0 - std::exp(-s)) / (2.0 * s);
        EXPECT_NEAR(faces[0].e0, 0.3 - 0.2 * kappa, 1e-9) << s;
        EXPECT_NEAR(faces[1].e0, 0.1 + 0.2 * kappa, 1e-9) << s;
        EXPECT_GE(faces[0].e0, faces[1].e0 - 1e-12) << s;
    }
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
