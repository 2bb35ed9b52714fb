#include "firn/geometry/ray_caster.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/geometry/box_triangle.h"
#include "firn/geometry/embree.h"
#include "firn/util/error.h"

namespace firn {

struct RayCaster::Impl {
    EmbreeScene embree;
    TriangleMesh owned;
    const TriangleMesh *mesh = nullptr;  // Embree's triangles (owned or borrowed): point queries, hits' normals
};

namespace {

// The point of triangle abc nearest to p (Ericson, "Real-Time Collision Detection", 2005, section 5.1.5).
glm::dvec3 closestPointOnTriangle(const glm::dvec3 &p, const glm::dvec3 &a, const glm::dvec3 &b, const glm::dvec3 &c) {
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return a;
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

struct ClosestQuery {
    const TriangleMesh *mesh;
    glm::dvec3 point;
    double distance;  // m, shrinks as nearer triangles are found
};

bool visitTriangle(RTCPointQueryFunctionArguments *args) {
    auto *q = static_cast<ClosestQuery *>(args->userPtr);
    const unsigned t = args->primID;
    const glm::dvec3 nearest = closestPointOnTriangle(q->point, q->mesh->vertex(t, 0), q->mesh->vertex(t, 1),
                                                      q->mesh->vertex(t, 2));
    const double d = glm::length(nearest - q->point);
    if (d >= q->distance) return false;
    q->distance = d;
    args->query->radius = static_cast<float>(d) * 1.0001f + 1e-7f;  // shrink the search, never below the exact d
    return true;
}

struct BoxQuery {
    const TriangleMesh *mesh;
    glm::dvec3 lo, hi;            // m
    std::vector<unsigned> found;  // triangles in the box
};

bool visitTriangleInBox(RTCPointQueryFunctionArguments *args) {
    auto *q = static_cast<BoxQuery *>(args->userPtr);
    const unsigned t = args->primID;
    if (triangleOverlapsBox(q->lo, q->hi, q->mesh->vertex(t, 0), q->mesh->vertex(t, 1), q->mesh->vertex(t, 2)))
        q->found.push_back(t);
    return false;  // the query's reach unchanged
}

}  // namespace

RayCaster::RayCaster(TriangleMesh mesh, Rays rays) : RayCaster(nullptr, std::move(mesh), rays) {}

std::unique_ptr<const RayCaster> RayCaster::over(const TriangleMesh &mesh, Rays rays) {
    return std::unique_ptr<const RayCaster>(new RayCaster(&mesh, TriangleMesh(), rays));
}

RayCaster::RayCaster(const TriangleMesh *borrowed, TriangleMesh owned, Rays rays)
    : impl_(std::make_unique<Impl>()), empty_(borrowed ? borrowed->empty() : owned.empty()) {
    RTCDevice device = impl_->embree.device;
    // Few rays per triangle: a fast build (Morton) beats a better tree. Many: the car's 10,644 occluder triangles
    // build in milliseconds either way and their queries take half the time on the SAH tree (docs/benchmarks.md,
    // car-profile).
    const RTCBuildQuality quality = rays == Rays::Few ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_MEDIUM;
    rtcSetSceneBuildQuality(impl_->embree.scene, quality);
    // Robust: a ray aimed at an edge two triangles share hits one of them. Without it a closed body lets rays
    // through its edges (1.9 % of rays aimed at a sphere's edges; the car's surface voxels 501,600 -> 500,313) for
    // 0.6 % of the bake's time (docs/benchmarks.md, car-speed, lead-robust53).
    rtcSetSceneFlags(impl_->embree.scene, RTC_SCENE_FLAG_ROBUST);
    if (!empty_) {
        impl_->owned = std::move(owned);  // kept: its triangles are Embree's index buffer
        impl_->mesh = borrowed ? borrowed : &impl_->owned;
        const TriangleMesh &kept = *impl_->mesh;
        static_assert(sizeof(glm::uvec3) == 3 * sizeof(unsigned), "Embree reads the triangles as packed UINT3");
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        // The triangles shared (a million: 12 MB not copied), and the vertices too when their array has the spare
        // vertex past the last one that Embree reads 16 bytes into (mesh.h); else they are copied.
        if (kept.positions.capacity() > kept.positions.size()) {
            rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, kept.positions.data(),
                                       0, sizeof(glm::vec3), kept.positions.size());
        } else {
            auto *vertices = static_cast<float *>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), kept.positions.size()));
            if (vertices)
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, kept.positions.size()),
                                  [&](const tbb::blocked_range<std::size_t> &r) {
                                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                                          for (int k = 0; k < 3; ++k) vertices[3 * i + k] = kept.positions[i][k];
                                  });
        }
        static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "Embree reads the vertices as packed FLOAT3");
        rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, kept.triangles.data(), 0,
                                   sizeof(glm::uvec3), kept.triangles.size());
        throwOnEmbreeError(device, "allocate the scene (out of memory?)");
        // The scene's quality alone leaves its one geometry's BVH at MEDIUM (SAH): 4x slower to build on 1M
        // triangles (0.33 s against 0.09 s, bench/snow_layer_bench.py's scene).
        rtcSetGeometryBuildQuality(geometry, quality);
        impl_->embree.attach(geometry);
    }
    impl_->embree.commit("build the scene");
}

RayCaster::~RayCaster() = default;

bool RayCaster::occluded(const glm::vec3 &origin, const glm::vec3 &direction, float tNear, float tFar) const {
    if (empty_) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = makeEmbreeRay(origin, direction, tNear, tFar);
    rtcOccluded1(impl_->embree.scene, &context, &ray);
    return ray.tfar < 0.0f;  // Embree marks a blocked ray with tfar = -inf
}

std::optional<RayCaster::Hit> RayCaster::intersect(const glm::vec3 &origin, const glm::vec3 &direction,
                                                   float tNear, float tFar) const {
    if (empty_) return std::nullopt;
    const RTCRayHit query = intersectEmbree(impl_->embree.scene, origin, direction, tNear, tFar);
    if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    // The normal of the triangle hit, not a table of them all: a million triangles' normals (12 MB, touched
    // once) cost more than the few thousand hits of a snow layer.
    const unsigned t = query.hit.primID;
    return Hit{query.ray.tfar, t, glm::normalize(impl_->mesh->crossNormal(t))};
}

std::optional<double> RayCaster::closestDistance(const glm::dvec3 &point, double maxDistance) const {
    if (empty_) return std::nullopt;
    RTCPointQuery query{};
    query.x = static_cast<float>(point.x), query.y = static_cast<float>(point.y), query.z = static_cast<float>(point.z);
    query.radius = static_cast<float>(maxDistance) * 1.0001f + 1e-7f;  // float rounding must not cull a triangle
    query.time = 0.0f;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    ClosestQuery closest{impl_->mesh, point, maxDistance};
    rtcPointQuery(impl_->embree.scene, &query, &context, visitTriangle, &closest);
    if (closest.distance >= maxDistance) return std::nullopt;
    return closest.distance;
}

std::vector<unsigned> RayCaster::trianglesInBox(const glm::dvec3 &lo, const glm::dvec3 &hi) const {
    if (empty_) return {};
    const glm::dvec3 centre = 0.5 * (lo + hi);
    RTCPointQuery query{};
    query.x = static_cast<float>(centre.x), query.y = static_cast<float>(centre.y), query.z = static_cast<float>(centre.z);
    // Reaching the box's corners from the centre as rounded to float: nothing in the box is culled.
    const double rounding = std::numeric_limits<float>::epsilon() *
                            std::max({std::abs(centre.x), std::abs(centre.y), std::abs(centre.z), 1.0});
    query.radius = static_cast<float>((0.5 * glm::length(hi - lo) + 2.0 * rounding) * 1.0001);
    query.time = 0.0f;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    BoxQuery box{impl_->mesh, lo, hi, {}};
    rtcPointQuery(impl_->embree.scene, &query, &context, visitTriangleInBox, &box);
    std::sort(box.found.begin(), box.found.end());
    return box.found;
}

}  // namespace firn
