#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/snow/snowfall.h"

namespace firn {

// One soft ball of snow (Nishita 1997). Balls stand in columns on landing sites. Snow is kept above the
// balls' own surface (the sites' tangent planes, averaged by field weight), so it never reaches below or
// inside the object it lies on.
struct Metaball {
    glm::vec3 centre;  // m
    float radius;      // m, where the field reaches zero
    glm::vec3 normal;  // unit normal of the site's surface: the column's axis
    float base;        // m: the surface lies this far below the centre along the normal (may be negative)
    float depth;       // m below the snow's top at the centre, along the normal (for compaction)
};

// Field value of the snow's iso-surface (the balls' peak is 1).
inline constexpr double kSnowIsoValue = 0.5;

struct MetaballLayoutSettings {
    double depth = 0.1;        // m of snow on open level ground
    double spacing = 0.05;     // m between landing sites
    double smoothness = 0.5;   // 0..1: radius/spacing from 1.25 (lumpy) to 2.5 (smooth)
    double randomness = 0.25;  // 0..1: seeded jitter of each column's depth (+-50 % at 1) and ball radii (+-20 %)
    std::uint64_t seed = 0;
};

double metaballRadius(const MetaballLayoutSettings &settings);  // m, before jitter

// Columns of balls on each site, layered so that the field's iso-surface over a uniformly covered surface
// lies at depth x site cover (the layer-averaged field of metaball.h sets the layer heights).
std::vector<Metaball> layoutMetaballs(const std::vector<LandingSite> &sites, const MetaballLayoutSettings &settings);

// The same layout with its column shapes solved once (bisections, some milliseconds) for many calls: a snow
// brush lays out a few columns per dab. `stream` picks an independent seeded jitter (0: layoutMetaballs's).
class MetaballColumns {
  public:
    explicit MetaballColumns(const MetaballLayoutSettings &settings);
    ~MetaballColumns();
    std::vector<Metaball> layout(const std::vector<LandingSite> &sites, std::uint64_t stream = 0) const;

  private:
    class Table;
    MetaballLayoutSettings settings_;
    std::unique_ptr<Table> table_;
};

}  // namespace firn
