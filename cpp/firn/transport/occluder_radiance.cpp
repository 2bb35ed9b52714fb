#include "firn/transport/occluder_radiance.h"

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "firn/geometry/closest_point.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

glm::dvec3 reflectedByOccluder(const Scene &scene, const glm::dvec3 &q, const glm::dvec3 &n, const Rgb &albedo,
                               const SkyRays &rays, std::uint64_t seed, std::uint64_t stream,
                               Medium::ColumnMarcher &marcher) {
    const glm::dvec3 reduced = reducedExtinctionPerDensity(scene.medium->optics());
    const double limit = columnLimit(reduced);
    const glm::dvec3 p = q + 1e-5 * n;
    glm::dvec3 irradiance(0.0);
    for (std::size_t b = 0; b < beamCount(scene); ++b) {
        const double cosine = glm::dot(n, towardsBeam(scene, b, p));
        if (cosine > 0.0) irradiance += cosine * glm::dvec3(beamAt(scene, b, p, 1, 0, 0, marcher).irradiance);
    }
    glm::dvec3 sky(0.0);
    for (int k = 0; k < rays.count(); ++k) {
        const glm::dvec3 w = rays.direction(n, k, seed, stream);
        if (scene.occluders->caster().occluded(glm::vec3(p), glm::vec3(w), 1e-5f)) continue;
        const double column = marcher.column(p, w, std::numeric_limits<double>::infinity(), limit);
        if (column < limit) sky += kPi * scene.sky.radianceFrom(w) * transmittance(reduced, column);
    }
    return albedo * (irradiance + sky / double(rays.count())) / kPi;
}

OccluderRadiance::OccluderRadiance(const Scene &scene, double cell, int skyRays, std::uint64_t seed)
    : scene_(scene), cell_(cell), rays_(skyRays), seed_(seed) {}

std::uint64_t OccluderRadiance::KeyHash::stream(const Key &key) {
    const std::uint64_t xy = std::uint64_t(std::uint32_t(key.cell.x())) << 32 | std::uint32_t(key.cell.y());
    const std::uint64_t zt = std::uint64_t(std::uint32_t(key.cell.z())) << 32 | key.triangle;
    return mix64(mix64(xy) ^ zt) ^ std::uint64_t(key.front);
}

glm::dvec3 OccluderRadiance::at(const glm::dvec3 &q, unsigned triangle, const glm::dvec3 &facing,
                                Medium::ColumnMarcher &marcher) const {
    const TriangleMesh &mesh = scene_.occluders->mesh();
    const glm::dvec3 normal = glm::normalize(glm::dvec3(mesh.crossNormal(triangle)));
    const glm::dvec3 cell = glm::floor(q / cell_);
    const Key key{openvdb::Coord(int(cell.x), int(cell.y), int(cell.z)), triangle, glm::dot(normal, facing) > 0.0};
    {
        decltype(cache_)::const_accessor found;
        if (cache_.find(found, key)) return found->second;
    }
    // Computed outside the table's lock; a thread that computed it meanwhile found the same value.
    const glm::dvec3 centre = (cell + 0.5) * cell_;
    const glm::dvec3 point = closestPointOnTriangle(centre, glm::dvec3(mesh.vertex(triangle, 0)),
                                                    glm::dvec3(mesh.vertex(triangle, 1)), glm::dvec3(mesh.vertex(triangle, 2)));
    const glm::dvec3 value = reflectedByOccluder(scene_, point, key.front ? normal : -normal, scene_.occluders->albedo(triangle),
                                              rays_, seed_, KeyHash::stream(key), marcher);
    cache_.insert({key, value});
    return value;
}

}  // namespace firn
