#include "firn/geometry/mesh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "firn/util/error.h"

namespace firn {

double TriangleMesh::area(std::size_t t) const { return 0.5 * glm::length(crossNormal(t)); }

namespace {

bool finite(const glm::vec3 &p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

}  // namespace

// Checked, copied and measured in parallel (a million triangles: 0.03 s serial, before anything else can start);
// an error names the first bad vertex or triangle, as a serial pass would.
TriangleMesh makeTriangleMesh(const float *positions, std::size_t vertexCount, const unsigned *indices,
                              std::size_t triangleCount) {
    TriangleMesh mesh;
    mesh.positions.reserve(vertexCount + 1);  // the spare vertex Embree reads into (mesh.h)
    mesh.positions.resize(vertexCount);
    const auto point = [&](std::size_t i) {
        return glm::vec3(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
    };
    std::atomic<bool> nonFinite{false};
    const float extent = tbb::parallel_reduce(  // m, largest |coordinate|
        tbb::blocked_range<std::size_t>(0, vertexCount), 0.0f,
        [&](const tbb::blocked_range<std::size_t> &r, float largest) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const glm::vec3 p = point(i);
                if (!finite(p)) {
                    nonFinite = true;
                    continue;
                }
                mesh.positions[i] = p;
                largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
            }
            return largest;
        },
        [](float a, float b) { return std::max(a, b); });
    if (nonFinite)
        for (std::size_t i = 0; i < vertexCount; ++i)
            if (!finite(point(i)))
                throw InvalidArgument("vertex " + std::to_string(i) + " has a non-finite coordinate (NaN or inf)");
    // Area below (1e-6 of the extent)^2 is rounding noise, not a surface.
    const double minArea = std::pow(1e-6 * std::max(extent, 1e-3f), 2.0);
    const auto corners = [&](std::size_t t) { return glm::uvec3(indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]); };
    const auto inRange = [&](const glm::uvec3 &tri) {
        return tri.x < vertexCount && tri.y < vertexCount && tri.z < vertexCount;
    };
    enum : std::uint8_t { kKept, kDegenerate, kOutOfRange };
    std::vector<std::uint8_t> fate(triangleCount);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangleCount), [&](const tbb::blocked_range<std::size_t> &r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            const glm::uvec3 tri = corners(t);
            if (!inRange(tri)) {
                fate[t] = kOutOfRange;
                continue;
            }
            const glm::vec3 a = mesh.positions[tri.x], b = mesh.positions[tri.y], c = mesh.positions[tri.z];
            fate[t] = 0.5 * glm::length(glm::cross(b - a, c - a)) <= minArea ? kDegenerate : kKept;  // as area()
        }
    });
    mesh.triangles.reserve(triangleCount);
    for (std::size_t t = 0; t < triangleCount; ++t) {
        if (fate[t] == kOutOfRange) {
            const glm::uvec3 tri = corners(t);
            const unsigned bad = tri.x >= vertexCount ? tri.x : tri.y >= vertexCount ? tri.y : tri.z;
            throw InvalidArgument("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(bad) +
                                  " of " + std::to_string(vertexCount));
        }
        if (fate[t] == kKept) mesh.triangles.push_back(corners(t));
        else ++mesh.droppedDegenerate;
    }
    return mesh;
}

namespace {

// Each mesh's triangles offset in parallel (a million: 0.03 s serial, on the way to Embree).
TriangleMesh joined(const std::vector<const TriangleMesh *> &meshes) {
    TriangleMesh out;
    std::size_t vertices = 0, triangles = 0;
    for (const TriangleMesh *m : meshes) vertices += m->positions.size(), triangles += m->triangles.size();
    out.positions.reserve(vertices + 1);  // the spare vertex Embree reads into (mesh.h)
    out.triangles.resize(triangles);
    std::size_t at = 0;
    for (const TriangleMesh *part : meshes) {
        const TriangleMesh &m = *part;
        const auto offset = static_cast<unsigned>(out.positions.size());
        out.positions.insert(out.positions.end(), m.positions.begin(), m.positions.end());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.triangles.size()),
                          [&](const tbb::blocked_range<std::size_t> &r) {
                              for (std::size_t t = r.begin(); t != r.end(); ++t)
                                  out.triangles[at + t] = m.triangles[t] + offset;
                          });
        at += m.triangles.size();
        out.droppedDegenerate += m.droppedDegenerate;
    }
    return out;
}

}  // namespace

TriangleMesh merge(std::initializer_list<const TriangleMesh *> meshes) { return joined(meshes); }

TriangleMesh merge(const std::vector<TriangleMesh> &meshes) {
    std::vector<const TriangleMesh *> parts;
    for (const TriangleMesh &m : meshes) parts.push_back(&m);
    return joined(parts);
}

}  // namespace firn
