#include "firn/transport/sun_clearance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "firn/transport/link_triangles.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

// rad: beyond the disc's radius, the float rounding of a ray's direction (a few 1e-8 per component).
constexpr double kDirectionRounding = 1e-6;
// A triangle's plane is used where the rays outpace its rise across at least twofold (slope x drift <= 1/2): then a
// ray that starts above it stays above it.
constexpr double kSteepest = 0.5;
constexpr double kMarginVoxels = 4.0;     // how far around the medium's bounds the grid reaches
constexpr double kWidestReachCells = 16;  // a disc whose drift spans more cells gets no pre-test
constexpr std::int64_t kMostCells = std::int64_t(1) << 24;

}  // namespace

SunClearance::SunClearance(const Medium &medium, const Occluders &occluders, const SunLight &sun) {
    const double radius = 0.5 * sun.angularDiameter + kDirectionRounding;
    if (occluders.empty() || radius >= 0.25 * kPi) return;
    up_ = glm::normalize(sun.direction);
    u_ = glm::normalize(glm::cross(std::abs(up_.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0), up_));
    v_ = glm::cross(up_, u_);
    drift_ = std::tan(radius);
    pad_ = linkPad(medium, occluders);
    const auto across = [&](const glm::dvec3 &x) { return glm::dvec2(glm::dot(x, u_), glm::dot(x, v_)); };

    // The grid over the medium's bounds grown by the margin, as the sun sees them.
    const double margin = kMarginVoxels * medium.voxelSize();
    glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    lowest_ = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 8; ++k) {
        const glm::dvec3 corner((k & 1 ? medium.boundsMax() : medium.boundsMin()).x,
                                (k & 2 ? medium.boundsMax() : medium.boundsMin()).y,
                                (k & 4 ? medium.boundsMax() : medium.boundsMin()).z);
        lo = glm::min(lo, across(corner)), hi = glm::max(hi, across(corner));
        lowest_ = std::min(lowest_, glm::dot(corner, up_));
    }
    lowest_ -= margin, lo -= margin, hi += margin;
    cell_ = medium.voxelSize();
    const glm::dvec2 span = hi - lo;
    if (span.x * span.y / (cell_ * cell_) > double(kMostCells)) cell_ = std::sqrt(span.x * span.y / double(kMostCells));
    origin_ = lo;

    // The triangles as the sun sees them; those wholly below every query's start never shade one.
    const TriangleMesh &mesh = occluders.mesh();
    highest_ = -std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
        std::array<glm::dvec2, 3> p;
        std::array<double, 3> z;
        for (int k = 0; k < 3; ++k) {
            const glm::dvec3 x(mesh.vertex(t, k));
            p[k] = across(x), z[k] = glm::dot(x, up_);
        }
        Across a;
        a.top = std::max({z[0], z[1], z[2]});
        highest_ = std::max(highest_, a.top);
        if (a.top + pad_ < lowest_) continue;
        a.lo = glm::min(p[0], glm::min(p[1], p[2])), a.hi = glm::max(p[0], glm::max(p[1], p[2]));
        for (int k = 0; k < 3; ++k) {
            const glm::dvec2 edge = p[(k + 1) % 3] - p[k], other = p[(k + 2) % 3] - p[k];
            const double length = glm::length(edge);
            glm::dvec2 n = length > 0.0 ? glm::dvec2(edge.y, -edge.x) / length : glm::dvec2(0.0);
            if (glm::dot(n, other) > 0.0) n = -n;
            a.normal[k] = n;
            a.extent[k] = std::max({glm::dot(n, p[0]), glm::dot(n, p[1]), glm::dot(n, p[2])});
        }
        // The plane z = height + slope . (q - corner) through the three corners (its normal (a, b, z) crosswise).
        const glm::dvec3 e1(p[1] - p[0], z[1] - z[0]), e2(p[2] - p[0], z[2] - z[0]);
        const glm::dvec3 n = glm::cross(e1, e2);
        if (std::abs(n.z) >= 1e-6 * glm::length(n)) {
            a.slope = glm::dvec2(-n.x / n.z, -n.y / n.z);
            a.planar = glm::length(a.slope) * drift_ <= kSteepest;
        }
        a.corner = p[0], a.height = z[0];
        triangles_.push_back(a);
    }
    reach_ = std::max(0.0, highest_ - lowest_) * drift_ + 3.0 * pad_;
    if (triangles_.empty() || reach_ > kWidestReachCells * cell_) return;
    columns_ = std::max(1, int(std::ceil(span.x / cell_))), rows_ = std::max(1, int(std::ceil(span.y / cell_)));

    // Each cell lists the triangles whose box across, grown by reach_, meets it (counted, then filled).
    const auto cells = [&](const Across &a, const auto &each) {
        const int c0 = std::max(0, int(std::floor((a.lo.x - reach_ - origin_.x) / cell_)));
        const int c1 = std::min(columns_ - 1, int(std::floor((a.hi.x + reach_ - origin_.x) / cell_)));
        const int r0 = std::max(0, int(std::floor((a.lo.y - reach_ - origin_.y) / cell_)));
        const int r1 = std::min(rows_ - 1, int(std::floor((a.hi.y + reach_ - origin_.y) / cell_)));
        for (int r = r0; r <= r1; ++r)
            for (int c = c0; c <= c1; ++c) each(std::size_t(r) * columns_ + c);
    };
    start_.assign(std::size_t(columns_) * rows_ + 1, 0);
    for (const Across &a : triangles_) cells(a, [&](std::size_t c) { ++start_[c + 1]; });
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    listed_.resize(start_.back());
    std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
        cells(triangles_[t], [&](std::size_t c) { listed_[next[c]++] = std::uint32_t(t); });
}

std::int64_t SunClearance::cellOf(const glm::dvec2 &p) const {
    const double c = std::floor((p.x - origin_.x) / cell_), r = std::floor((p.y - origin_.y) / cell_);
    if (!(c >= 0.0 && r >= 0.0 && c < columns_ && r < rows_)) return -1;
    return std::int64_t(r) * columns_ + std::int64_t(c);
}

bool SunClearance::cleared(const Across &t, const glm::dvec2 &p, double height) const {
    if (t.top + pad_ < height) return true;  // wholly below the ray's start
    // Across, a ray reaches no farther than its drift up to the triangle's top.
    const double reach = (t.top - height) * drift_ + 3.0 * pad_;
    if (p.x < t.lo.x - reach || p.x > t.hi.x + reach || p.y < t.lo.y - reach || p.y > t.hi.y + reach) return true;
    for (int k = 0; k < 3; ++k)
        if (glm::dot(t.normal[k], p) - t.extent[k] > reach) return true;
    // Its plane under the start lies below it and rises across slower than the rays drift: the rays stay above it.
    if (!t.planar) return false;
    const double slope = glm::length(t.slope);
    return t.height + glm::dot(t.slope, p - t.corner) + (4.0 + 2.0 * slope) * pad_ < height;
}

bool SunClearance::clear(const glm::dvec3 &point) const {
    if (columns_ == 0) return false;
    const double height = glm::dot(point, up_);
    if (height < lowest_) return false;  // the cells' lists hold only the triangles a query from lowest_ up may meet
    if (height > highest_ + pad_) return true;
    const glm::dvec2 p(glm::dot(point, u_), glm::dot(point, v_));
    const std::int64_t c = cellOf(p);
    if (c < 0) return false;
    for (std::uint32_t k = start_[std::size_t(c)]; k < start_[std::size_t(c) + 1]; ++k)
        if (!cleared(triangles_[listed_[k]], p, height)) return false;
    return true;
}

std::vector<std::shared_ptr<const SunClearance>> sunClearances(const Scene &scene) {
    std::vector<std::shared_ptr<const SunClearance>> out;
    if (scene.occluders->empty()) return out;
    for (const SunLight &sun : scene.suns)
        out.push_back(std::make_shared<const SunClearance>(*scene.medium, *scene.occluders, sun));
    return out;
}

}  // namespace firn
