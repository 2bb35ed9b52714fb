#include "firn/snow/level_of_detail.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "firn/util/error.h"

namespace firn {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Spacing over voxel size at the finest level is the user's; a piece of target this many spacings across may
// straddle a band boundary (it takes the finer band), so that splitting ends.
constexpr double kStraddleSpacings = 4.0;
// A piece straddling the view's edge is split until it is this small against its distance.
constexpr double kViewEdgeFraction = 0.25;

struct Piece {
    std::array<glm::vec3, 3> p;
    std::array<float, 3> w;
};

struct Sphere {
    glm::dvec3 centre;
    double radius;
};

Sphere boundingSphere(const Piece &t) {
    const glm::dvec3 c = (glm::dvec3(t.p[0]) + glm::dvec3(t.p[1]) + glm::dvec3(t.p[2])) / 3.0;
    double r = 0.0;
    for (const glm::vec3 &v : t.p) r = std::max(r, glm::length(glm::dvec3(v) - c));
    return {c, r};
}

// Halves the longest edge: two pieces of the same plane, weights linear along the edge.
std::array<Piece, 2> bisect(const Piece &t) {
    int e = 0;  // edge from corner e to e + 1
    double longest = -1.0;
    for (int i = 0; i < 3; ++i) {
        const double len = glm::length(t.p[(i + 1) % 3] - t.p[i]);
        if (len > longest) longest = len, e = i;
    }
    const int a = e, b = (e + 1) % 3, c = (e + 2) % 3;
    const glm::vec3 m = 0.5f * (t.p[a] + t.p[b]);
    const float wm = 0.5f * (t.w[a] + t.w[b]);
    return {Piece{{t.p[a], m, t.p[c]}, {t.w[a], wm, t.w[c]}}, Piece{{m, t.p[b], t.p[c]}, {wm, t.w[b], t.w[c]}}};
}

}  // namespace

bool CameraFootprint::mayView(const glm::dvec3 &centre, double radius) const {
    if (viewHalfAngle >= kPi) return true;
    const glm::dvec3 to = centre - position;
    const double d = glm::length(to);
    if (d <= radius) return true;
    const double off = std::acos(std::clamp(glm::dot(to, forward) / d, -1.0, 1.0));
    return off - std::asin(radius / d) <= viewHalfAngle;
}

void CameraFootprint::validate() const {
    const double sum = position.x + position.y + position.z;
    if (!std::isfinite(sum)) throw InvalidArgument("camera position must be finite");
    if (!(std::abs(glm::length(forward) - 1.0) < 1e-3))
        throw InvalidArgument("camera view direction must be a unit vector");
    if (!(pixelAngle > 1e-7 && pixelAngle < 0.1))
        throw InvalidArgument("camera pixel angle must be between 1e-7 and 0.1 rad (got " +
                              std::to_string(pixelAngle) + ")");
    if (!(viewHalfAngle > 0.0)) throw InvalidArgument("camera view half-angle must be positive");
}

int lodLevel(double distance, const CameraFootprint &camera, double fineVoxel, int bands) {
    const double pixels = camera.footprint(distance) / fineVoxel;  // fine voxels per pixel
    if (!(pixels >= 2.0)) return 0;
    return std::min(bands - 1, int(std::floor(std::log2(pixels))));
}

double lodVoxelSize(int level, double fineVoxel) { return std::ldexp(fineVoxel, level); }

std::vector<LodBand> lodBands(const CameraFootprint &camera, double fineVoxel, double spacing, double farthest,
                              int maxBands) {
    const int count = lodLevel(farthest, camera, fineVoxel, maxBands) + 1;
    std::vector<LodBand> bands(count);
    for (int k = 0; k < count; ++k) {
        LodBand &b = bands[k];
        b.level = k;
        b.voxelSize = lodVoxelSize(k, fineVoxel);
        b.spacing = std::ldexp(spacing, k);
        // Level k starts where a pixel spans its voxel.
        b.nearDistance = k == 0 ? 0.0 : b.voxelSize / camera.pixelAngle;
        b.farDistance = k + 1 < count ? lodVoxelSize(k + 1, fineVoxel) / camera.pixelAngle
                                      : std::numeric_limits<double>::infinity();
    }
    return bands;
}

BandTargets splitTargetsByBand(const TriangleMesh &targets, const std::vector<float> &weights,
                               const CameraFootprint &camera, const std::vector<LodBand> &bands, double fineVoxel) {
    const int count = int(bands.size());
    std::vector<std::vector<glm::vec3>> positions(count);
    std::vector<std::vector<float>> pieceWeights(count);
    BandTargets out;
    const auto level = [&](double distance) { return lodLevel(distance, camera, fineVoxel, count); };
    std::vector<Piece> stack;
    for (std::size_t t = 0; t < targets.triangleCount(); ++t) {
        Piece piece;
        for (int i = 0; i < 3; ++i) {
            piece.p[i] = targets.vertex(t, i);
            piece.w[i] = weights.empty() ? 1.0f : weights[targets.triangles[t][i]];
        }
        stack.push_back(piece);
        while (!stack.empty()) {
            const Piece p = stack.back();
            stack.pop_back();
            const Sphere s = boundingSphere(p);
            const double d = glm::length(s.centre - camera.position);
            const double nearest = std::max(0.0, d - s.radius), farthest = d + s.radius;
            const int k = level(nearest);
            // The snow reaches a few spacings beyond its target: kept in view if it may show.
            if (!camera.mayView(s.centre, s.radius + 3.0 * bands[k].spacing)) {
                ++out.outOfView;
                continue;
            }
            const bool oneBand = level(farthest) == k;
            // In view, and small against its distance where it may cross the view's edge: what it holds out of
            // view costs little.
            const bool settled = camera.viewHalfAngle >= kPi ||
                                 (camera.mayView(s.centre, 0.0) && s.radius <= kViewEdgeFraction * nearest);
            const bool small = s.radius <= kStraddleSpacings * bands[k].spacing;
            if (small || (oneBand && settled)) {
                positions[k].insert(positions[k].end(), p.p.begin(), p.p.end());
                pieceWeights[k].insert(pieceWeights[k].end(), p.w.begin(), p.w.end());
            } else {
                for (const Piece &half : bisect(p)) stack.push_back(half);
            }
        }
    }
    for (int k = 0; k < count; ++k) {
        std::vector<unsigned> indices(positions[k].size());
        for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = unsigned(i);
        out.meshes.push_back(makeTriangleMesh(reinterpret_cast<const float *>(positions[k].data()),
                                              positions[k].size(), indices.data(), indices.size() / 3));
        out.weights.push_back(weights.empty() ? std::vector<float>{} : std::move(pieceWeights[k]));
    }
    return out;
}

}  // namespace firn
