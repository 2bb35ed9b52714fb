#pragma once

#include <limits>
#include <memory>
#include <vector>

#include "firn/geometry/mesh.h"
#include "firn/geometry/ray_caster.h"
#include "firn/transport/lamps.h"
#include "firn/transport/lights.h"
#include "firn/transport/medium.h"
#include "firn/util/color.h"

namespace firn {

// Opaque, diffusely reflecting scene surfaces: they cast shadows on and in the snow, block the sky, and
// reflect light back into snow lying on them (the ground under the snow shows through thin snow).
class Occluders {
  public:
    Occluders() = default;  // none
    // One diffuse albedo per triangle, each channel in [0, 1]. Throws InvalidArgument.
    Occluders(TriangleMesh mesh, std::vector<Rgb> albedo);

    bool empty() const { return mesh_.empty(); }
    const TriangleMesh &mesh() const { return mesh_; }
    const RayCaster &caster() const { return *caster_; }
    const Rgb &albedo(unsigned triangle) const { return albedo_[triangle]; }
    // Whether the triangle belongs to a closed surface (one with an inside; an open sheet has none).
    bool closed(unsigned triangle) const { return closed_[triangle]; }
    // False where `p` lies off the closed triangles' bounding box (always, without one: most scenes, open ground
    // planes): then not both of the rays from it straight up and down meet one, so it is enclosed by none.
    bool mayEnclose(const glm::vec3 &p) const;
    // The closed triangles sharing a point with the axis-aligned box [lo, hi] (m), ascending; none, at the cost of a
    // bounding-box check, where the box lies off all closed triangles' bounding box.
    std::vector<unsigned> closedIn(const glm::dvec3 &lo, const glm::dvec3 &hi) const;

  private:
    TriangleMesh mesh_;
    std::vector<Rgb> albedo_;
    std::vector<char> closed_;
    // m: the closed triangles' bounding box; without one empty, [+inf, -inf], which holds no point.
    glm::dvec3 closedMin_{std::numeric_limits<double>::infinity()};
    glm::dvec3 closedMax_{-std::numeric_limits<double>::infinity()};
    std::shared_ptr<const RayCaster> caster_ = std::make_shared<RayCaster>(TriangleMesh{});
};

// Everything that lights or shadows the snow.
struct Scene {
    std::shared_ptr<const Medium> medium;
    std::vector<SunLight> suns;
    std::vector<Lamp> lamps;
    Sky sky;
    std::shared_ptr<const Occluders> occluders = std::make_shared<Occluders>();
};

// Throws InvalidArgument if a light is malformed or the medium is missing.
void validate(const Scene &scene);

}  // namespace firn
