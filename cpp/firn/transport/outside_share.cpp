#include "firn/transport/outside_share.h"

#include <vector>

#include "firn/geometry/box_triangle.h"

namespace firn {

namespace {

constexpr int kLevels = 3;  // a cut box is halved down to 1/8 voxel (2^-kLevels), then holds one jittered point
// Voxels: boxes are tested shrunk by this much, so that a triangle lying on a face (a surface mesh on the lattice's
// planes) does not cut them; far above the float rounding of the mesh's vertices.
constexpr double kFaceTolerance = 1e-4;

struct DensitySums {
    double all = 0.0, outside = 0.0;  // kg: the density's integral over the voxel, and over its part outside
};

// Adds the density's integral over the cube [lo, lo + size] (m), one cell of the trilinear density or part of one,
// and over its part outside, to `sums`: exact by the midpoint rule where no triangle of `cutting` (closed) crosses
// it (wholly on one side), else by its eight halves down to kLevels, there one jittered point.
class CutCubes {
  public:
    CutCubes(const Medium &medium, Medium::Accessor &density, const Occluders &occluders, const PhotonTracer &tracer,
             Rng &rng)
        : medium_(medium), density_(density), mesh_(occluders.mesh()), tracer_(tracer), rng_(rng),
          tolerance_(kFaceTolerance * medium.voxelSize()) {}

    void integrate(const glm::dvec3 &lo, double size, int level, const std::vector<unsigned> &cutting,
                   DensitySums &sums) {
        const std::vector<unsigned> crossing = within(lo, size, cutting);
        if (crossing.empty()) return add(lo + 0.5 * size, size, sums);
        if (level == kLevels)
            return add(lo + size * glm::dvec3(rng_.uniform(), rng_.uniform(), rng_.uniform()), size, sums);
        for (int k = 0; k < 8; ++k)
            integrate(lo + 0.5 * size * glm::dvec3(k & 1, k >> 1 & 1, k >> 2), 0.5 * size, level + 1, crossing, sums);
    }

  private:
    // The triangles of `candidates` that cross the cube [lo, lo + size] shrunk by the tolerance.
    std::vector<unsigned> within(const glm::dvec3 &lo, double size, const std::vector<unsigned> &candidates) const {
        std::vector<unsigned> out;
        for (unsigned t : candidates)
            if (triangleOverlapsBox(lo + tolerance_, lo + (size - tolerance_), mesh_.vertex(t, 0), mesh_.vertex(t, 1),
                                    mesh_.vertex(t, 2)))
                out.push_back(t);
        return out;
    }

    // A cube of side `size` (m) standing for its point p.
    void add(const glm::dvec3 &p, double size, DensitySums &sums) {
        const double mass = medium_.densityAt(p, density_) * size * size * size;
        sums.all += mass;
        if (mass > 0.0 && !tracer_.enclosed(p)) sums.outside += mass;
    }

    const Medium &medium_;
    Medium::Accessor &density_;
    const TriangleMesh &mesh_;
    const PhotonTracer &tracer_;
    Rng &rng_;
    double tolerance_;  // m
};

}  // namespace

// The voxel's cube tested exactly against the closed triangles (Occluders::closedIn): uncut, it lies wholly on the
// side of its centre. Cut, its eighths each lie in one cell of the trilinear density (the cells' planes pass through
// voxel centres), where the midpoint rule is exact: the eighths and their halves that no triangle crosses count
// exactly, and only the smallest cut ones hold a jittered point. Main's 9 probes (the centre, 0.45 voxel towards each
// corner) missed a closed occluder thinner than 0.9 voxel between them (a ski); its jittered points in all 8^3
// strata ... (docs/benchmarks.md "occluder-share").
double outsideShare(const Medium &medium, Medium::Accessor &density, const Occluders &occluders,
                    const PhotonTracer &tracer, const openvdb::Coord &c, Rng &rng) {
    const double h = medium.voxelSize(), tolerance = kFaceTolerance * h;
    const glm::dvec3 centre = medium.voxelCentre(c), lo = centre - 0.5 * h;
    const std::vector<unsigned> cutting = occluders.closedIn(lo + tolerance, lo + (h - tolerance));
    if (cutting.empty()) return tracer.enclosed(centre) ? 0.0 : 1.0;
    DensitySums sums;
    CutCubes cubes(medium, density, occluders, tracer, rng);
    for (int k = 0; k < 8; ++k)
        cubes.integrate(lo + 0.5 * h * glm::dvec3(k & 1, k >> 1 & 1, k >> 2), 0.5 * h, 1, cutting, sums);
    return sums.all > 0.0 ? sums.outside / sums.all : 0.0;
}

}  // namespace firn
