#include "firn/grains/accumulation.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "firn/geometry/ray_caster.h"
#include "firn/grains/cell_hash.h"
#include "firn/grains/sphere_scene.h"
#include "firn/util/error.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

// Candidate rays traced in parallel against what lay there when the batch began, then accepted in order:
// the batch size, not the thread count, decides the result.
constexpr std::size_t kBatchSize = 256;
// Recent grains wait in the column grid until they are as many as those in the Embree scene (at least this
// many): rebuilding at each doubling keeps the total build work within twice that of the final scene.
constexpr std::size_t kMinRebuild = 4096;

// Every grain, binned by centre in cubes of side 2 r_max: a grain can only overlap grains in the 27 cubes
// around its own centre. A hash grid answers this point query in O(1), which Embree's BVH (built for rays and
// rebuilt in batches) cannot beat for grains that arrive one at a time.
class OverlapGrid {
  public:
    explicit OverlapGrid(double cell) : cell_(cell) {}

    void insert(unsigned grain, const glm::dvec3 &centre) {
        const glm::dvec3 c = glm::floor(centre / cell_);
        cells_.insert(CellHash::key(std::int64_t(c.x), std::int64_t(c.y), std::int64_t(c.z)), grain);
    }

    // True if a grain (centre, radius) would press into a neighbour deeper than the tolerance.
    bool overlaps(const GrainSet &grains, const glm::dvec3 &centre, double radius) const {
        const glm::dvec3 c = glm::floor(centre / cell_);
        bool overlap = false;
        const auto pressesInto = [&](unsigned other) {
            const double rOther = grains.radii[other];
            const double allowed = radius + rOther - kGrainOverlapTolerance * std::min(radius, rOther);
            const glm::dvec3 gap = grains.centres[other] - centre;
            overlap = glm::dot(gap, gap) < allowed * allowed;
            return !overlap;
        };
        for (int di = -1; di <= 1 && !overlap; ++di)
            for (int dj = -1; dj <= 1 && !overlap; ++dj)
                for (int dk = -1; dk <= 1 && !overlap; ++dk)
                    cells_.forEach(CellHash::key(std::int64_t(c.x) + di, std::int64_t(c.y) + dj, std::int64_t(c.z) + dk),
                                   pressesInto);
        return overlap;
    }

  private:
    double cell_;  // m
    CellHash cells_;
};

// Grains not yet in the Embree scene, binned by the squares (side 2 r_max) of the plane across the fall that
// their shadow touches: a falling ray can only meet the grains of its own square.
class ColumnGrid {
  public:
    ColumnGrid(const Frame &frame, double cell) : frame_(frame), cell_(cell) {}

    void insert(unsigned grain, const glm::dvec3 &centre, double radius) {
        const double u = glm::dot(centre, frame_.t), v = glm::dot(centre, frame_.b);
        const auto i0 = index(u - radius), i1 = index(u + radius), j0 = index(v - radius), j1 = index(v + radius);
        for (auto i = i0; i <= i1; ++i)
            for (auto j = j0; j <= j1; ++j) cells_.insert(CellHash::key(i, j, 0), grain);
    }
    void clear() { cells_.clear(); }

    // The nearest grain with index >= `first` that the ray (unit direction along the fall) enters.
    std::optional<SphereScene::Hit> intersect(const GrainSet &grains, const glm::dvec3 &origin,
                                              const glm::dvec3 &direction, unsigned first) const {
        std::optional<SphereScene::Hit> nearest;
        // A cell's grains come newest first, so those from `first` on come before any older one.
        cells_.forEach(CellHash::key(index(glm::dot(origin, frame_.t)), index(glm::dot(origin, frame_.b)), 0),
                       [&](unsigned grain) {
                           if (grain < first) return false;
                           const auto t = raySphereEntry(origin, direction, grains.centres[grain], grains.radii[grain]);
                           if (t && (!nearest || *t < nearest->distance))
                               nearest = SphereScene::Hit{*t, grain, glm::normalize(origin + *t * direction - grains.centres[grain])};
                           return true;
                       });
        return nearest;
    }

  private:
    std::int64_t index(double x) const { return static_cast<std::int64_t>(std::floor(x / cell_)); }
    Frame frame_;
    double cell_;  // m
    CellHash cells_;
};

// What a falling ray met first.
struct Landing {
    double distance = std::numeric_limits<double>::infinity();  // m from the ray origin
    glm::dvec3 normal{0.0};  // unit, facing the incoming ray
    bool found() const { return std::isfinite(distance); }
    void consider(double t, const glm::dvec3 &n) {
        if (t < distance) distance = t, normal = n;
    }
};

struct Candidate {
    glm::dvec3 origin;  // m, on the start plane
    double radius;      // m, of the grain it would place
    Landing landing;
};

// The first triangle on the ray, its distance solved again in double precision.
void landOnTriangles(const RayCaster &caster, const TriangleMesh &mesh, const glm::dvec3 &direction, Candidate &c) {
    const auto hit = caster.intersect(glm::vec3(c.origin), glm::vec3(direction));
    if (!hit) return;
    const glm::dvec3 a = mesh.vertex(hit->triangle, 0);
    glm::dvec3 n = glm::normalize(glm::dvec3(mesh.crossNormal(hit->triangle)));
    const double along = glm::dot(direction, n);
    const double t = std::abs(along) > 1e-12 ? glm::dot(a - c.origin, n) / along : double(hit->distance);
    if (along > 0.0) n = -n;  // either winding: the side the snow falls on
    c.landing.consider(t, n);
}

std::string metres(double value) {
    std::ostringstream text;
    text << std::setprecision(3) << value << " m";
    return text.str();
}

double facingCosine(const glm::dvec3 &normal, const glm::dvec3 &direction) { return -glm::dot(normal, direction); }

}  // namespace

void validate(const AccumulationSettings &s) {
    if (s.count == 0) throw InvalidArgument("grain count must be at least 1");
    if (s.count > kMaxGrainCount)
        throw BudgetExceeded("grain count " + std::to_string(s.count) + " exceeds the limit of " +
                             std::to_string(kMaxGrainCount) + " grains (about 100 bytes each while accumulating)");
    if (!(s.radius > 0.0 && s.radius <= kMaxGrainRadius))
        throw InvalidArgument("grain radius must be a length in (0, 1000] m");
    if (!(s.radiusVariation >= 0.0 && s.radiusVariation < 1.0))
        throw InvalidArgument("grain radius variation must be in [0, 1): radius r (1 + sigma u), u in [-1, 1]");
    const double length = glm::length(s.direction);
    if (!(length > 0.0) || !std::isfinite(length)) throw InvalidArgument("snowfall direction must be a non-zero vector");
    if (!(s.maxSlope >= 0.0 && s.maxSlope <= 0.5 * kPi))
        throw InvalidArgument("maximum slope must be between 0 and 90 degrees");
}

AccumulationResult accumulateGrains(const TriangleMesh &mesh, const AccumulationSettings &settings, Progress *progress) {
    validate(settings);
    if (mesh.empty()) throw InvalidArgument("grains need triangles to land on: the scene has none");
    const glm::dvec3 fall = glm::normalize(settings.direction);
    const Frame frame(fall);  // t, b span the plane across the fall
    const double rMax = settings.radius * (1.0 + settings.radiusVariation);
    const double cosMaxSlope = std::cos(settings.maxSlope);
    const std::size_t maxRays = settings.maxRays ? settings.maxRays : 20 * settings.count + 10000;

    // Where rays start: the scene's extent across the fall (grown by r_max), above everything along it.
    double uMin = 1e300, uMax = -1e300, vMin = 1e300, vMax = -1e300, wTop = 1e300, wBottom = -1e300;
    for (const glm::vec3 &p : mesh.positions) {
        const glm::dvec3 q(p);
        const double u = glm::dot(q, frame.t), v = glm::dot(q, frame.b), w = glm::dot(q, fall);
        uMin = std::min(uMin, u), uMax = std::max(uMax, u), vMin = std::min(vMin, v), vMax = std::max(vMax, v);
        wTop = std::min(wTop, w), wBottom = std::max(wBottom, w);
    }
    const double extent = std::max({uMax - uMin, vMax - vMin, wBottom - wTop});  // m
    // Grains below float precision at the scene's size could not be told apart by Embree or the grids' indices.
    if (rMax < 1e-6 * extent)
        throw InvalidArgument("grain radius " + metres(settings.radius) + " is too small for a scene " +
                              metres(extent) + " across (at least 1e-6 of it)");
    uMin -= rMax, uMax += rMax, vMin -= rMax, vMax += rMax;

    const RayCaster caster(mesh);
    AccumulationResult result;
    GrainSet &grains = result.grains;
    grains.centres.reserve(settings.count), grains.radii.reserve(settings.count);
    OverlapGrid overlapGrid(2.0 * rMax);
    ColumnGrid recentGrid(frame, 2.0 * rMax);
    std::unique_ptr<SphereScene> committed = std::make_unique<SphereScene>(grains, 0);
    std::vector<Candidate> batch(kBatchSize);

    while (grains.size() < settings.count && result.rays < maxRays) {
        if (progress) {
            progress->throwIfCancelled();
            progress->report(double(grains.size()) / double(settings.count), "Accumulating grains");
        }
        if (grains.size() - committed->size() >= std::max(kMinRebuild, committed->size())) {
            committed = std::make_unique<SphereScene>(grains);
            recentGrid.clear();
        }
        const std::size_t batchSize = std::min(kBatchSize, maxRays - result.rays);
        // Far enough above the highest grain that a whole batch stacking in one column stays below the start.
        const double wStart = wTop - 2.0 * rMax * double(batchSize + 2);
        const auto firstNew = static_cast<unsigned>(grains.size());
        const std::size_t firstRay = result.rays;

        tbb::parallel_for(std::size_t(0), batchSize, [&](std::size_t i) {
            Rng rng(settings.seed, firstRay + i);
            const double u = uMin + (uMax - uMin) * rng.uniform(), v = vMin + (vMax - vMin) * rng.uniform();
            Candidate &c = batch[i];
            c.origin = u * frame.t + v * frame.b + wStart * fall;
            c.radius = settings.radius * (1.0 + settings.radiusVariation * (2.0 * rng.uniform() - 1.0));
            c.landing = Landing{};
            landOnTriangles(caster, mesh, fall, c);
            if (const auto hit = committed->intersect(c.origin, fall, c.landing.distance)) c.landing.consider(hit->distance, hit->normal);
            if (const auto hit = recentGrid.intersect(grains, c.origin, fall, 0)) c.landing.consider(hit->distance, hit->normal);
        });

        for (std::size_t i = 0; i < batchSize && grains.size() < settings.count; ++i) {
            Candidate &c = batch[i];
            ++result.rays;
            // Grains placed earlier in this batch were not there when the ray was traced.
            if (const auto hit = recentGrid.intersect(grains, c.origin, fall, firstNew)) c.landing.consider(hit->distance, hit->normal);
            if (!c.landing.found()) {
                ++result.missed;
                continue;
            }
            if (facingCosine(c.landing.normal, fall) < cosMaxSlope) {
                ++result.steep;
                continue;
            }
            const glm::dvec3 hitPoint = c.origin + c.landing.distance * fall;
            const glm::dvec3 centre = hitPoint + c.radius * c.landing.normal;
            if (overlapGrid.overlaps(grains, centre, c.radius) ||
                caster.closestDistance(centre, c.radius * (1.0 - kGrainOverlapTolerance))) {
                ++result.overlapping;
                continue;
            }
            const auto index = static_cast<unsigned>(grains.size());
            grains.add(centre, c.radius);
            overlapGrid.insert(index, centre);
            recentGrid.insert(index, centre, c.radius);
            wTop = std::min(wTop, glm::dot(centre, fall) - c.radius);
        }
    }
    if (progress) progress->report(1.0, "Accumulating grains");
    return result;
}

}  // namespace firn
