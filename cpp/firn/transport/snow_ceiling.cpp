#include "firn/transport/snow_ceiling.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace firn {

SnowCeiling::SnowCeiling(const openvdb::FloatGrid &density) {
    const openvdb::CoordBBox box = density.evalActiveVoxelBoundingBox();
    // Over a few voxels scattered far apart the map would outgrow the grid itself: none then, and no ray is proven.
    const double columns = (double(box.max().x()) - box.min().x() + 2.0) * (double(box.max().y()) - box.min().y() + 2.0);
    if (!(columns <= double(density.activeVoxelCount()) + kFewColumns)) return;
    mapped_ = true;
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
    for (std::size_t level = 0; level < tiles_.size(); ++level) {
        const int edge = kTileEdges[level];
        Tiles &tiles = tiles_[level];
        tiles.nx = nx_ / edge + 1, tiles.ny = ny_ / edge + 1;
        tiles.highest.assign(std::size_t(tiles.nx) * tiles.ny, kNone);
        for (int y = 0; y < ny_; ++y)
            for (int x = 0; x < nx_; ++x) {
                const int c = ceiling_[std::size_t(y) * nx_ + x];
                // Into every tile whose widened box holds column (x, y): its own and the neighbours one column away.
                for (int ty = (y - 1) / edge; ty <= std::min((y + 1) / edge, tiles.ny - 1); ++ty)
                    for (int tx = (x - 1) / edge; tx <= std::min((x + 1) / edge, tiles.nx - 1); ++tx) {
                        if (tx < 0 || ty < 0) continue;
                        int &t = tiles.highest[std::size_t(ty) * tiles.nx + tx];
                        t = std::max(t, c);
                    }
            }
    }
}

std::size_t SnowCeiling::bytes() const {
    std::size_t n = ceiling_.capacity();
    for (const Tiles &tiles : tiles_) n += tiles.highest.capacity();
    return n * sizeof(int);
}

double SnowCeiling::tileExit(const glm::dvec3 &o, const glm::dvec3 &direction, int tx, int ty, int edge) const {
    double exit = std::numeric_limits<double>::infinity();
    const double low[2] = {double(min_.x() + tx * edge), double(min_.y() + ty * edge)};
    for (int a = 0; a < 2; ++a) {
        if (direction[a] > 0.0) exit = std::min(exit, (low[a] + edge - o[a]) / direction[a]);
        if (direction[a] < 0.0) exit = std::min(exit, (low[a] - o[a]) / direction[a]);
    }
    return exit;
}

int SnowCeiling::ceiling(int x, int y) const {
    x -= min_.x(), y -= min_.y();
    if (x < 0 || y < 0 || x >= nx_ || y >= ny_ || ceiling_[std::size_t(y) * nx_ + x] == kNone) return kNone;
    return ceiling_[std::size_t(y) * nx_ + x] + min_.z();
}

bool SnowCeiling::clearAbove(const glm::dvec3 &o, const glm::dvec3 &direction) const {
    if (!mapped_ || !(direction.z > 0.0)) return false;
    if (highest_ == kNone) return true;
    // Steps of one voxel along the ray (index space): each step's points lie in the cell columns its xy box
    // touches, at or above the step's first z (the ray rises). The margin covers the rounding of the column walk's
    // own sample points (Medium::ColumnMarcher::column), which lie on the same line.
    constexpr double kMargin = 1e-6;  // voxels
    const double top = double(highest_ + min_.z()) + 1.0;  // every point at or above it lies above all snow
    const double xLow = min_.x(), xHigh = min_.x() + nx_, yLow = min_.y(), yHigh = min_.y() + ny_;
    for (double t = 0.0;;) {
        const glm::dvec3 a = o + t * direction, b = o + (t + 1.0) * direction;
        if (a.z - kMargin >= top) return true;
        // Beyond the map's columns and moving away: no snow further on.
        if ((direction.x >= 0.0 && a.x - kMargin >= xHigh) || (direction.x <= 0.0 && a.x + kMargin <= xLow) ||
            (direction.y >= 0.0 && a.y - kMargin >= yHigh) || (direction.y <= 0.0 && a.y + kMargin <= yLow))
            return true;
        const int cellZ = int(std::floor(a.z - kMargin));
        // Above the whole tile holding a (coarsest first): on to where the ray leaves it. Its points up to there
        // lie within the tile, or within the margin of it, at or above a's z.
        const double tileJump = [&] {
            for (std::size_t level = 0; level < tiles_.size(); ++level) {
                const int edge = kTileEdges[level];
                const Tiles &tiles = tiles_[level];
                const int tx = int(std::floor((a.x - min_.x()) / edge)), ty = int(std::floor((a.y - min_.y()) / edge));
                if (tx < 0 || ty < 0 || tx >= tiles.nx || ty >= tiles.ny) return t;  // the plain steps decide
                if (cellZ > tiles.highest[std::size_t(ty) * tiles.nx + tx]) return tileExit(o, direction, tx, ty, edge);
            }
            return t;
        }();
        if (tileJump > t) {
            t = tileJump;
            continue;
        }
        const int x0 = int(std::floor(std::min(a.x, b.x) - kMargin)), x1 = int(std::floor(std::max(a.x, b.x) + kMargin));
        const int y0 = int(std::floor(std::min(a.y, b.y) - kMargin)), y1 = int(std::floor(std::max(a.y, b.y) + kMargin));
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x)
                if (cellZ <= ceiling(x, y)) return false;
        t += 1.0;
    }
}

}  // namespace firn
