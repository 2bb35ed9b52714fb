#include "firn/snow/snow_brush.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <unordered_map>

#include <glm/vec2.hpp>

#include <glm/geometric.hpp>
#include <openvdb/tools/Interpolation.h>
#include <tbb/parallel_for.h>

#include "firn/snow/snowfall.h"
#include "firn/util/error.h"
#include "firn/util/random.h"

namespace firn {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxSitesPerDab = 1e6;  // a dab is a brush touch, not a whole layer
// The plastic-number Kronecker sequence (Roberts 2018), as snowfall.cpp places sites: stratified in the disc.
constexpr double kR2a = 0.7548776662466927, kR2b = 0.5698402909980532;
const glm::vec3 kUp(0.0f, 0.0f, 1.0f);

double fract(double x) { return x - std::floor(x); }

void checkDab(const Dab &d) {
    const auto bad = [](const char *what, double value) {
        throw InvalidArgument(std::string("brush ") + what + " out of range (got " + std::to_string(value) + ")");
    };
    if (!std::isfinite(d.centre.x + d.centre.y + d.centre.z)) bad("location (not finite)", d.centre.x);
    if (!(d.radius > 0.0 && d.radius <= 1000.0)) bad("radius: 0 to 1000 m", d.radius);
    if (!(d.strength >= 0.0 && d.strength <= 100.0)) bad("strength: 0 to 100 m", d.strength);
    if (!(d.pressure >= 0.0 && d.pressure <= 1.0)) bad("pressure: 0 to 1", d.pressure);
}

}  // namespace

// Where a dab acts: a cylinder along the snowfall through its centre, `reach` m up and down, with a smooth
// falloff of the strength across it.
struct SnowCanvas::Footprint {
    glm::vec3 centre, fall, across1, across2;  // fall: unit, the way snow falls; across: unit, perpendicular
    double radius, reach, strength;            // m

    // m of depth at `point`: strength x (1 - rho^2/R^2)^2 at rho m from the axis; 0 outside the cylinder.
    double weight(const glm::vec3 &point) const {
        const glm::vec3 d = point - centre;
        const float along = glm::dot(d, fall);
        const double rho2 = double(glm::dot(d, d) - along * along) / (radius * radius);
        if (rho2 >= 1.0 || std::abs(along) > reach) return 0.0;
        return strength * (1.0 - rho2) * (1.0 - rho2);
    }
};

SnowCanvas::SnowCanvas(std::vector<Metaball> balls, SnowGrids grids, const SnowLayerSettings &settings,
                       const TriangleMesh &targets, const TriangleMesh &occluders)
    : settings_((settings.validate(), settings)), raster_(settings.raster()), columns_(settings.layout()),
      balls_(std::move(balls)), live_(balls_.size(), true), index_(balls_, raster_.voxelSize),
      grids_(std::move(grids)), targetTriangles_(targets.triangleCount()), scene_(merge({&targets, &occluders})) {
    if (!grids_.density || !grids_.surface) throw InvalidArgument("the snow needs its density and surface grids");
    const double h = grids_.surface->voxelSize()[0];
    if (std::abs(h - raster_.voxelSize) > 1e-6 * raster_.voxelSize)
        throw InvalidArgument("the snow's grids have voxels of " + std::to_string(h) + " m, its settings " +
                              std::to_string(raster_.voxelSize) + " m: rebuild it from its metaballs first");
    if (targets.empty()) throw InvalidArgument("no target triangles to paint snow on");
}

SnowCanvas::~SnowCanvas() = default;

std::vector<Metaball> SnowCanvas::metaballs() const {
    std::vector<Metaball> out;
    out.reserve(balls_.size());
    for (std::size_t i = 0; i < balls_.size(); ++i)
        if (live_[i]) out.push_back(balls_[i]);
    return out;
}

std::vector<std::uint32_t> SnowCanvas::ballsUnder(const Footprint &brush) const {
    std::vector<std::uint32_t> ids;
    for (std::size_t i = 0; i < balls_.size(); ++i)
        if (live_[i] && brush.weight(balls_[i].centre) > 0.0) ids.push_back(std::uint32_t(i));
    return ids;
}

double SnowCanvas::snowHeight(const glm::vec3 &point, const glm::vec3 &normal) const {
    // March up the level set (a signed distance: each step can be as long as its value) to its zero crossing.
    const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sdf(*grids_.surface);
    const double h = raster_.voxelSize;
    double t = 0.0;
    for (int step = 0; step < 100000 && t < 100.0; ++step) {
        const glm::vec3 x = point + normal * float(t);
        const double phi = sdf.wsSample(openvdb::Vec3d(x.x, x.y, x.z));
        if (phi >= 0.0) return std::max(0.0, t - phi);
        t += std::max(-phi, 0.25 * h);
    }
    return t;
}

std::vector<Metaball> SnowCanvas::landColumns(const Footprint &brush) {
    const double spacing = settings_.spacing;
    const double expected = kPi * brush.radius * brush.radius / (spacing * spacing);
    if (expected > kMaxSitesPerDab)
        throw BudgetExceeded("a brush of radius " + std::to_string(brush.radius) + " m would place " +
                             std::to_string(expected) + " columns of snow per dab at the layer's spacing of " +
                             std::to_string(spacing) + " m: use a smaller radius");
    const std::size_t count = std::size_t(std::ceil(expected));
    Rng rng(settings_.seed ^ 0xB2D5ull, dabs_);
    const double shiftU = rng.uniform(), shiftV = rng.uniform();
    const SnowfallSettings snowfall = settings_.snowfall();
    const float eps = float(1e-4 * spacing) + 1e-5f;  // m, leaves the surface (as findLandingSites)

    struct Landing {
        LandingSite site;
        float height;  // m of snow already above the surface there
    };
    std::vector<std::optional<Landing>> landings(count);
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
        // Stratified in the disc (square-root map), then down the snowfall onto the first surface.
        const double rho = brush.radius * std::sqrt(fract(shiftU + (i + 1) * kR2a));
        const double phi = 2.0 * kPi * fract(shiftV + (i + 1) * kR2b);
        const glm::vec3 top = brush.centre + brush.across1 * float(rho * std::cos(phi)) +
                              brush.across2 * float(rho * std::sin(phi)) - brush.fall * float(brush.reach);
        const auto hit = scene_.intersect(top, brush.fall, 0.0f, float(2.0 * brush.reach));
        if (!hit || hit->triangle >= targetTriangles_) return;  // nothing there, or not a target
        const glm::vec3 p = top + brush.fall * hit->distance;
        const glm::vec3 n = glm::dot(hit->normal, brush.fall) > 0.0f ? -hit->normal : hit->normal;
        const double slope = std::acos(std::clamp(double(glm::dot(n, kUp)), -1.0, 1.0));
        Rng siteRng(settings_.seed ^ 0xB2D5ull, (dabs_ << 24) + i);
        const double u = siteRng.uniform(), v = siteRng.uniform();
        const double cover = slopeCover(slope, settings_.maxSlope) *
                             snowfallExposure(p + n * eps, n, scene_, snowfall, u, v);
        const double depth = brush.weight(p) * cover;  // m this dab adds here
        if (!(depth > 0.01 * brush.strength)) return;
        const float height = float(snowHeight(p, n));
        landings[i] = Landing{{p + n * height, n, float(depth / settings_.depth)}, height};
    });

    std::vector<Metaball> balls;
    for (std::size_t i = 0; i < count; ++i) {
        if (!landings[i]) continue;
        // Each column its own jitter stream; its balls stand on the object's surface, below the old snow.
        for (Metaball b : columns_.layout({landings[i]->site}, (dabs_ << 24) + i + 1)) {
            b.base += landings[i]->height;
            balls.push_back(b);
        }
    }
    return balls;
}

void SnowCanvas::change(std::uint32_t id, const Metaball &to, std::vector<openvdb::Coord> &dirty) {
    index_.leavesOf(balls_[id], dirty);
    if (index_.sameLeaves(balls_[id], to)) {  // a new depth, a small move: the index stays as it is
        balls_[id] = to;
        return;
    }
    index_.erase(id, balls_[id]);
    balls_[id] = to;
    index_.insert(id, to);
    index_.leavesOf(to, dirty);
}

void SnowCanvas::remove(std::uint32_t id, std::vector<openvdb::Coord> &dirty) {
    index_.leavesOf(balls_[id], dirty);
    index_.erase(id, balls_[id]);
    live_[id] = false;
}

std::uint32_t SnowCanvas::add(const Metaball &ball, std::vector<openvdb::Coord> &dirty) {
    const auto id = std::uint32_t(balls_.size());
    balls_.push_back(ball);
    live_.push_back(true);
    index_.insert(id, ball);
    index_.leavesOf(ball, dirty);
    return id;
}

void SnowCanvas::addSnow(const Footprint &brush, std::vector<openvdb::Coord> &dirty, DabStats &stats) {
    const std::vector<Metaball> landed = landColumns(brush);
    for (const Metaball &b : landed) add(b, dirty);
    stats.added = landed.size();
}

void SnowCanvas::eraseSnow(const Footprint &brush, std::vector<openvdb::Coord> &dirty, DabStats &stats) {
    // The top `weight` m of the snow goes: the balls that lay less deep than that, and the others rise that much
    // nearer the top (their compaction).
    for (const std::uint32_t id : ballsUnder(brush)) {
        Metaball b = balls_[id];
        const float w = float(brush.weight(b.centre));
        if (b.depth < w) {
            remove(id, dirty), ++stats.removed;
        } else {
            b.depth -= w;
            change(id, b, dirty), ++stats.changed;
        }
    }
}

void SnowCanvas::smoothSnow(const Footprint &brush, std::vector<openvdb::Coord> &dirty, DabStats &stats) {
    // Each column's top (its balls' base + depth: m above the surface along the normal) moves towards the mean top
    // of the columns within two spacings of it across the snowfall, at most `weight` m; the balls move with it.
    const std::vector<std::uint32_t> ids = ballsUnder(brush);
    const double near = 2.0 * settings_.spacing;
    // Neighbours from a grid of cells `near` wide across the snowfall: the 3 x 3 cells around a ball hold them all.
    const auto across = [&](const glm::vec3 &p) {
        const glm::vec3 d = p - brush.centre;
        return glm::dvec2(glm::dot(d, brush.across1), glm::dot(d, brush.across2));
    };
    const auto cellOf = [&](const glm::dvec2 &a) { return glm::ivec2(int(std::floor(a.x / near)), int(std::floor(a.y / near))); };
    const auto cellKey = [](const glm::ivec2 &c) { return (std::uint64_t(std::uint32_t(c.x)) << 32) | std::uint32_t(c.y); };
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells;
    for (std::size_t i = 0; i < ids.size(); ++i) cells[cellKey(cellOf(across(balls_[ids[i]].centre)))].push_back(i);

    std::vector<Metaball> moved(ids.size());
    tbb::parallel_for(std::size_t(0), ids.size(), [&](std::size_t i) {
        const Metaball &b = balls_[ids[i]];
        const glm::dvec2 at = across(b.centre);
        const glm::ivec2 cell = cellOf(at);
        double sum = 0.0, n = 0.0;
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy) {
                const auto found = cells.find(cellKey(cell + glm::ivec2(dx, dy)));
                if (found == cells.end()) continue;
                for (const std::uint32_t j : found->second) {
                    const Metaball &o = balls_[ids[j]];
                    const glm::dvec2 d = across(o.centre) - at;
                    if (glm::dot(d, d) <= near * near) sum += double(o.base) + o.depth, n += 1.0;
                }
            }
        const double w = brush.weight(b.centre);
        const float shift = float(std::clamp(sum / n - (double(b.base) + b.depth), -w, w));
        moved[i] = b;
        moved[i].centre += b.normal * shift;
        moved[i].base += shift;
    });
    for (std::size_t i = 0; i < ids.size(); ++i) change(ids[i], moved[i], dirty), ++stats.changed;
}

DabStats SnowCanvas::apply(const Dab &dab) {
    checkDab(dab);
    Footprint brush;
    brush.centre = dab.centre;
    brush.fall = glm::normalize(settings_.direction);
    const glm::vec3 helper = std::abs(brush.fall.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    brush.across1 = glm::normalize(glm::cross(brush.fall, helper));
    brush.across2 = glm::cross(brush.fall, brush.across1);
    brush.radius = dab.radius;
    // Up and down the snowfall: the radius, and room for deep snow above or below the point painted.
    brush.reach = dab.radius + 2.0 * settings_.depth;
    brush.strength = dab.strength * dab.pressure;
    ++dabs_;

    DabStats stats;
    std::vector<openvdb::Coord> dirty;
    if (brush.strength > 0.0) {
        if (dab.mode == BrushMode::Add) addSnow(brush, dirty, stats);
        else if (dab.mode == BrushMode::Erase) eraseSnow(brush, dirty, stats);
        else smoothSnow(brush, dirty, stats);
    }
    std::sort(dirty.begin(), dirty.end());
    dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
    rasterizeLeaves(balls_, index_, dirty, raster_, grids_);
    stats.leaves = dirty.size();
    return stats;
}

}  // namespace firn
