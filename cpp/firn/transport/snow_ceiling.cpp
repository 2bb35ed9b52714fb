#include "firn/transport/snow_ceiling.h"

#include <algorithm>
#include <cmath>

#include "firn/transport/medium.h"

namespace firn {

SnowCeiling::SnowCeiling(const Medium &medium) : medium_(medium) {
    const openvdb::FloatGrid &density = medium.density();
    const openvdb::CoordBBox box = density.evalActiveVoxelBoundingBox();
    // Cell c's corners reach voxels c .. c + 1: the cells over voxel columns x0 - 1 .. x1 (y alike) can read snow.
    min_ = box.min() - openvdb::Coord(1, 1, 0);
    nx_ = box.dim().x() + 1, ny_ = box.dim().y() + 1;
    std::vector<int> top(std::size_t(nx_) * ny_, kNone);  // per voxel column: its highest non-zero voxel's z
    for (auto it = density.cbeginValueOn(); it; ++it) {
        if (*it == 0.0f) continue;  // a zero corner adds nothing to the trilinear density (inactive voxels hold 0)
        const openvdb::Coord c = it.getCoord() - min_;
        int &t = top[std::size_t(c.y()) * nx_ + c.x()];
        t = std::max(t, c.z());
    }
    // A cell's ceiling: the highest of its four corner columns' (voxels x, x + 1 by y, y + 1); a cell z at or below a
    // corner voxel's z has that voxel among (or below) its corners.
    ceiling_.assign(top.size(), kNone);
    auto topAt = [&](int x, int y) { return x < nx_ && y < ny_ ? top[std::size_t(y) * nx_ + x] : kNone; };
    for (int y = 0; y < ny_; ++y)
        for (int x = 0; x < nx_; ++x) {
            const int c = std::max({topAt(x, y), topAt(x + 1, y), topAt(x, y + 1), topAt(x + 1, y + 1)});
            ceiling_[std::size_t(y) * nx_ + x] = c;
            highest_ = std::max(highest_, c);
        }
}

int SnowCeiling::ceiling(int x, int y) const {
    x -= min_.x(), y -= min_.y();
    if (x < 0 || y < 0 || x >= nx_ || y >= ny_ || ceiling_[std::size_t(y) * nx_ + x] == kNone) return kNone;
    return ceiling_[std::size_t(y) * nx_ + x] + min_.z();
}

bool SnowCeiling::clearAbove(const glm::dvec3 &origin, const glm::dvec3 &direction) const {
    if (!(direction.z > 0.0)) return false;
    if (highest_ == kNone) return true;
    // Steps of one voxel along the ray (index space): each step's points lie in the cell columns its xy box
    // touches, at or above the step's first z (the ray rises). The margin covers the rounding of the column walk's
    // own sample points (Medium::ColumnMarcher::column), which lie on the same line.
    constexpr double kMargin = 1e-6;  // voxels
    const glm::dvec3 o = medium_.worldToIndex(origin);
    const double top = double(highest_ + min_.z()) + 1.0;  // every point at or above it lies above all snow
    const double xLow = min_.x(), xHigh = min_.x() + nx_, yLow = min_.y(), yHigh = min_.y() + ny_;
    for (double t = 0.0;; t += 1.0) {
        const glm::dvec3 a = o + t * direction, b = o + (t + 1.0) * direction;
        if (a.z - kMargin >= top) return true;
        // Beyond the map's columns and moving away: no snow further on.
        if ((direction.x >= 0.0 && a.x - kMargin >= xHigh) || (direction.x <= 0.0 && a.x + kMargin <= xLow) ||
            (direction.y >= 0.0 && a.y - kMargin >= yHigh) || (direction.y <= 0.0 && a.y + kMargin <= yLow))
            return true;
        const int cellZ = int(std::floor(a.z - kMargin));
        const int x0 = int(std::floor(std::min(a.x, b.x) - kMargin)), x1 = int(std::floor(std::max(a.x, b.x) + kMargin));
        const int y0 = int(std::floor(std::min(a.y, b.y) - kMargin)), y1 = int(std::floor(std::max(a.y, b.y) + kMargin));
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x)
                if (cellZ <= ceiling(x, y)) return false;
    }
}

}  // namespace firn
