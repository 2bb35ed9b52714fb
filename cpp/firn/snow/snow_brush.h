#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/geometry/mesh.h"
#include "firn/geometry/ray_caster.h"
#include "firn/snow/metaball_layout.h"
#include "firn/snow/snow_layer.h"
#include "firn/snow/snow_rasterizer.h"

namespace firn {

// Snow by hand (Nishita et al. 1997's interactive placement, as a brush): dabs edit a snow layer's metaballs,
// the source of truth, and rasterize again only the 8^3 leaves the edited balls reach, so that the grids stay
// what rasterizeSnow would make of the same balls.

enum class BrushMode { Add, Erase, Smooth };

struct Dab {
    glm::vec3 centre{0.0f};  // m, world: a point on the surface painted (the snow's or the object's)
    double radius = 0.2;     // m, across the snowfall direction
    double strength = 0.02;  // m of depth a dab adds, removes, or moves the surface towards its neighbours' mean
    double pressure = 1.0;   // 0..1, scales the strength
    BrushMode mode = BrushMode::Add;
};

struct DabStats {
    std::size_t added = 0, removed = 0, changed = 0;  // balls
    std::size_t leaves = 0;                            // 8^3 leaves rasterized again
};

class SnowCanvas {
  public:
    // `balls` and `grids` as rasterizeSnow made them with `settings` (the layer's); `targets` take snow, the
    // targets and `occluders` shelter it (as generateSnowLayer sees them). Throws InvalidArgument for bad
    // settings or balls, or grids whose voxel size is not the settings'.
    SnowCanvas(std::vector<Metaball> balls, SnowGrids grids, const SnowLayerSettings &settings,
               const TriangleMesh &targets, const TriangleMesh &occluders);
    ~SnowCanvas();

    // Add: columns of balls land on the targets under the brush where the snowfall reaches them (sheltering and
    // slope as in generation), on top of the snow already there, `strength` x pressure deep at the centre and
    // falling off smoothly to the radius. Erase: removes that much from the top of the balls under the brush.
    // Smooth: moves the tops of the columns under the brush towards their neighbours' mean, at most that much.
    // Throws InvalidArgument for a non-finite centre or a radius, strength or pressure out of range.
    DabStats apply(const Dab &dab);

    std::vector<Metaball> metaballs() const;  // the live balls, in order
    const SnowGrids &grids() const { return grids_; }

  private:
    struct Footprint;
    std::vector<std::uint32_t> ballsUnder(const Footprint &brush) const;
    std::vector<Metaball> landColumns(const Footprint &brush);
    void addSnow(const Footprint &brush, std::vector<openvdb::Coord> &dirty, DabStats &stats);
    void eraseSnow(const Footprint &brush, std::vector<openvdb::Coord> &dirty, DabStats &stats);
    void smoothSnow(const Footprint &brush, std::vector<openvdb::Coord> &dirty, DabStats &stats);
    double snowHeight(const glm::vec3 &point, const glm::vec3 &normal) const;  // m of snow above a point
    void change(std::uint32_t id, const Metaball &to, std::vector<openvdb::Coord> &dirty);
    void remove(std::uint32_t id, std::vector<openvdb::Coord> &dirty);
    std::uint32_t add(const Metaball &ball, std::vector<openvdb::Coord> &dirty);

    SnowLayerSettings settings_;
    RasterSettings raster_;
    MetaballColumns columns_;
    std::vector<Metaball> balls_;
    std::vector<bool> live_;
    LeafBallIndex index_;
    SnowGrids grids_;
    std::size_t targetTriangles_;
    RayCaster scene_;  // targets first, then occluders
    std::uint64_t dabs_ = 0;
};

}  // namespace firn
