#include "firn/transport/edge_lobe.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "firn/util/random.h"
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

// The sun skimming a grazing face's density ramp beyond a lit edge, against a beam marched through that ramp: the
// beam crosses the lit face's plane (normal +x) at u0 voxels out from the grazing face's half-density plane (normal
// +y), u0 uniform over the half voxel where the trilinear fill 1/2 - u is not zero; it travels along -w, leaving the
// ramp at |n . w| per unit way; where its free path (in optical depths, tau a voxel at the snow's density) ends within
// the ramp it scatters once by HG(g), and counts where its new direction heads back through the grazing face's plane.
// Per unit area of that face: half a voxel of strip, times the lit face's cosine, times that chance.
TEST(EdgeLobe, SkimmedThroughRampMatchesAMarchedBeam) {
    const glm::dvec3 lit(1.0, 0.0, 0.0), grazing(0.0, 1.0, 0.0);
    const std::vector<glm::dvec3> normals{lit, grazing};
    for (const double tau : {2.0, 8.0})
        for (const double g : {0.0, 0.7})
            for (const double away : {0.0, 0.1, 0.5}) {  // -n . w: the beam leaving the grazing face's ramp
                const glm::dvec3 w = glm::normalize(glm::dvec3(0.5, -away, 0.8));
                Rng rng(7, std::uint64_t(100 * tau + 10 * g + 1000 * away));
                constexpr int kBeams = 100000;
                constexpr double kStep = 0.01;  // voxels of way, the fill read at each step's middle
                const double out = -glm::dot(grazing, w) * kStep;
                double back = 0.0;
                for (int k = 0; k < kBeams; ++k) {
                    double u = 0.5 * rng.uniform(), depth = 0.0;
                    const double freePath = -std::log(1.0 - rng.uniform());
                    while (u < 0.5 && depth < freePath) depth += tau * std::max(0.0, 0.5 - u - 0.5 * out) * kStep, u += out;
                    if (!(depth >= freePath)) continue;
                    const glm::dvec3 after = sampleHenyeyGreenstein(-w, g, rng.uniform(), rng.uniform());
                    if (glm::dot(after, grazing) < 0.0) back += 1.0;
                }
                const double marched = 0.5 * glm::dot(lit, w) * back / kBeams;
                const double skimmed = skimmedThroughRamp(normals, grazing, w, tau, g);
                EXPECT_NEAR(skimmed, marched, 0.03 * marched + 1e-4) << "tau " << tau << " g " << g << " away " << away;
            }
    // None where the face faces the light itself (its own intake holds those rays).
    EXPECT_EQ(skimmedThroughRamp(normals, grazing, glm::normalize(glm::dvec3(0.5, 0.2, 0.8)), 8.0, 0.7), 0.0);
}

// The air diagonal to an edge between a lit wall (+x, radiance 0.3) and the bottom beneath it (-z, 0.05): the faces'
// light reaches it only travelling away from both, so towards a camera above (w . -z < 0) it shows little, where the
// faces' lobes' mean showed half the wall's light; its lobe keeps the light T carries over the directions both faces
// face, its axis along T's first moment (by a finer quadrature here than the core's 128 directions).
TEST(EdgeLobe, AirBeyondTwoFacesShowsOnlyLightLeavingBoth) {
    const glm::dvec3 wall(1.0, 0.0, 0.0), bottom(0.0, 0.0, -1.0);
    const SourceLobe wallLobe = exitLobe(0.3, glm::dvec3(0.0), wall), bottomLobe = exitLobe(0.05, glm::dvec3(0.0), bottom);
    const FaceLobes faces{{{{wall, wallLobe.l0, wallLobe.l1}, {bottom, bottomLobe.l0, bottomLobe.l1}}}, 2};
    const SourceLobe lobe = lobeBeyondFaces(faces);
    constexpr int n = 400;
    double light = 0.0, shown = 0.0;  // over the directions both faces face, per unit solid angle / 4 pi
    glm::dvec3 moment(0.0);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double mu = -1.0 + 2.0 * (i + 0.5) / n, phi = 2.0 * kPi * (j + 0.5) / n, s = std::sqrt(1.0 - mu * mu);
            const glm::dvec3 w(s * std::cos(phi), s * std::sin(phi), mu);
            const double a = glm::dot(wall, w), b = glm::dot(bottom, w);
            if (a <= 0.0 || b <= 0.0) continue;
            const double T =
                (a * lobeRadiance(wallLobe.l0, wallLobe.l1, w) + b * lobeRadiance(bottomLobe.l0, bottomLobe.l1, w)) / (a + b);
            light += T / (double(n) * n), moment += T * w / (double(n) * n);
            shown += lobeRadiance(lobe.l0, lobe.l1, w) / (double(n) * n);
        }
    EXPECT_NEAR(shown, light, 0.03 * light);
    EXPECT_GT(glm::dot(glm::normalize(lobe.l1), glm::normalize(moment)), 0.999);
    const glm::dvec3 above = glm::normalize(glm::dvec3(0.354, -0.612, 0.707));  // box_sharp's worst block's camera
    const double faceMean = 0.5 * (lobeRadiance(wallLobe.l0, wallLobe.l1, above) +
                                   lobeRadiance(bottomLobe.l0, bottomLobe.l1, above));
    const double seenAbove = lobeRadiance(lobe.l0, lobe.l1, above);
    std::printf("towards the camera above: %.4f, the faces' lobes' mean %.4f\n", seenAbove, faceMean);
    EXPECT_LT(seenAbove, 0.5 * faceMean);
}

}  // namespace firn
