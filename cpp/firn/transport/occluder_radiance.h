#pragma once

#include <cstdint>

#include <glm/vec3.hpp>
#include <tbb/concurrent_hash_map.h>

#include "firn/transport/incident_light.h"
#include "firn/transport/scene.h"

namespace firn {

// Radiance (W/m^2/sr) an occluder's diffuse surface at q (unit normal n facing the viewer, albedo) sends after one
// reflection of the beams (one ray each, towards the sun's centre or the lamp's) and the sky (`rays`, cosine-weighted
// around n, the k-th drawn from (seed, stream, k)), through snow and past other occluders.
glm::dvec3 reflectedByOccluder(const Scene &scene, const glm::dvec3 &q, const glm::dvec3 &n, const Rgb &albedo,
                               const SkyRays &rays, std::uint64_t seed, std::uint64_t stream,
                               Medium::ColumnMarcher &marcher);

// The occluders' reflected radiance cached over a lattice of cubic cells: a cell's value for a triangle's side is
// reflectedByOccluder at the triangle's point nearest the cell's centre, with the sky's rays seeded by (cell,
// triangle, side) alone, so it does not depend on which ray asked first or on which thread. Sun shadows and sky
// light vary slowly over a car's body or the ground under it: one estimate with many rays per cell stands in for
// one ray per hit (the car: 1.1 M sky rays meet an occluder, a few tens of thousands of cells).
class OccluderRadiance {
  public:
    // cell: m, the lattice's edge; skyRays: rays per cell value.
    OccluderRadiance(const Scene &scene, double cell, int skyRays, std::uint64_t seed);

    // Radiance leaving `triangle` at q (on it) towards a viewer on the side `facing` points to. Thread-safe.
    glm::dvec3 at(const glm::dvec3 &q, unsigned triangle, const glm::dvec3 &facing, Medium::ColumnMarcher &marcher) const;

    std::size_t cells() const { return cache_.size(); }

  private:
    struct Key {
        openvdb::Coord cell;
        unsigned triangle;
        bool front;  // the side the triangle's counter-clockwise normal points to
        bool operator==(const Key &other) const {
            return cell == other.cell && triangle == other.triangle && front == other.front;
        }
    };
    struct KeyHash {
        static std::uint64_t stream(const Key &key);
        std::size_t hash(const Key &key) const { return std::size_t(stream(key)); }
        bool equal(const Key &a, const Key &b) const { return a == b; }
    };

    const Scene &scene_;
    double cell_;
    SkyRays rays_;
    std::uint64_t seed_;
    mutable tbb::concurrent_hash_map<Key, glm::dvec3, KeyHash> cache_;
};

}  // namespace firn
