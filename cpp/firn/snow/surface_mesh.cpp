#include "firn/snow/surface_mesh.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <string>

#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "firn/util/error.h"
#include "firn/util/openvdb_library.h"

namespace firn {

namespace {

constexpr float kHalfWidth = 3.0f;  // voxels of narrow band each side, as the rasterizer writes (vdb-contract.md)
constexpr int kMaxCoarsening = 64;  // voxel size factor beyond which a snow layer has no shape left to mesh

std::size_t triangleCount(const openvdb::tools::VolumeToMesh &mesher) {
    std::size_t n = 0;
    const openvdb::tools::PolygonPoolList &pools = mesher.polygonPoolList();
    for (std::size_t i = 0; i < mesher.polygonPoolListSize(); ++i)
        n += pools[i].numTriangles() + 2 * pools[i].numQuads();
    return n;
}

SurfaceMesh collect(openvdb::tools::VolumeToMesh &mesher, double adaptivity, double voxelSize) {
    SurfaceMesh mesh;
    mesh.adaptivity = adaptivity;
    mesh.voxelSize = voxelSize;
    mesh.vertices.assign(mesher.pointList().get(), mesher.pointList().get() + mesher.pointListSize());
    mesh.triangles.reserve(triangleCount(mesher));
    const openvdb::tools::PolygonPoolList &pools = mesher.polygonPoolList();
    // OpenVDB winds polygons clockwise seen from outside (negative inside); reversed here.
    for (std::size_t i = 0; i < mesher.polygonPoolListSize(); ++i) {
        const openvdb::tools::PolygonPool &pool = pools[i];
        for (std::size_t t = 0; t < pool.numTriangles(); ++t) {
            const openvdb::Vec3I &v = pool.triangle(t);
            mesh.triangles.emplace_back(v[2], v[1], v[0]);
        }
        for (std::size_t q = 0; q < pool.numQuads(); ++q) {
            const openvdb::Vec4I &v = pool.quad(q);
            mesh.triangles.emplace_back(v[3], v[2], v[1]);
            mesh.triangles.emplace_back(v[3], v[1], v[0]);
        }
    }
    return mesh;
}

SurfaceMesh mesh(const openvdb::FloatGrid &grid, double isovalue, double adaptivity) {
    openvdb::tools::VolumeToMesh mesher(isovalue, adaptivity);
    mesher(grid);
    return collect(mesher, adaptivity, grid.voxelSize()[0]);
}

// A leaf's voxels as 8 words of 64 bits, word x, bit (y << 3) | z: NodeMask<3>'s layout.
using LeafWords = std::array<std::uint64_t, 8>;
static_assert(openvdb::FloatTree::LeafNodeType::LOG2DIM == 3 && openvdb::FloatTree::LeafNodeType::NodeMaskType::WORD_COUNT == 8,
              "the word layout below is that of an 8^3 leaf's NodeMask<3>");
constexpr std::uint64_t kAllBits = ~std::uint64_t(0);
constexpr std::uint64_t kBelowTopZ = 0x7F7F7F7F7F7F7F7FULL;  // z < 7
constexpr std::uint64_t kTopZ = ~kBelowTopZ;                  // z = 7
constexpr std::uint64_t kBottomZ = kTopZ >> 7;                // z = 0
constexpr std::uint64_t kBelowTopY = 0x00FFFFFFFFFFFFFFULL;   // y < 7
constexpr std::uint64_t kTopY = ~kBelowTopY;                  // y = 7
constexpr std::uint64_t kBottomY = kTopY >> 56;               // y = 0

// Which voxels of `leaf` lie below `iso`.
LeafWords insideBits(const openvdb::FloatTree::LeafNodeType &leaf, float iso) {
    LeafWords inside{};
    const float *values = leaf.buffer().data();
    for (int row = 0; row < 64; ++row) {  // a column of 8 voxels along z: one byte
        unsigned byte = 0;
        for (int z = 0; z < 8; ++z) byte |= unsigned(values[8 * row + z] < iso) << z;
        inside[row >> 3] |= std::uint64_t(byte) << (8 * (row & 7));
    }
    return inside;
}

// Which voxels of `leaf`'s face `layer` (0 or 7) across `axis` lie below `iso`; the other bits 0.
LeafWords faceInsideBits(const openvdb::FloatTree::LeafNodeType &leaf, float iso, int axis, int layer) {
    LeafWords inside{};
    const float *values = leaf.buffer().data();
    for (int u = 0; u < 8; ++u)
        for (int w = 0; w < 8; ++w) {
            const int i = axis == 0 ? (layer << 6) | (u << 3) | w
                                    : (axis == 1 ? (u << 6) | (layer << 3) | w : (u << 6) | (w << 3) | layer);
            inside[i >> 6] |= std::uint64_t(values[i] < iso) << (i & 63);
        }
    return inside;
}

// The active and inside bits of the leaf next to `origin`'s one leaf along `axis` (`side` -1 or +1), on its face
// that touches: a leaf's own, or a tile's value and state repeated.
struct Neighbour {
    LeafWords active, inside;
};
Neighbour neighbourBits(openvdb::tree::ValueAccessor<const openvdb::FloatTree> &tree, const openvdb::Coord &origin,
                        int axis, int side, float iso) {
    using Leaf = openvdb::FloatTree::LeafNodeType;
    openvdb::Coord at = origin;
    at[axis] += side * int(Leaf::DIM);
    Neighbour n{};
    if (const Leaf *leaf = tree.probeConstLeaf(at)) {
        for (int x = 0; x < 8; ++x) n.active[x] = leaf->getValueMask().template getWord<std::uint64_t>(x);
        n.inside = faceInsideBits(*leaf, iso, axis, side > 0 ? 0 : 7);
    } else {
        const bool on = tree.isValueOn(at), below = tree.getValue(at) < iso;
        n.active.fill(on ? kAllBits : 0), n.inside.fill(below ? kAllBits : 0);
    }
    return n;
}

// The triangles volume-to-mesh without adaptivity makes of `grid`: one quad (two triangles) for each edge between
// neighbouring voxels on either side of the isovalue, one of them active. Counting them is a fraction of
// meshing, so a budget's search meshes once. A leaf's edges are counted 64 at a time on its masks' words:
// inside the leaf, and across each face against the neighbouring leaf (or tile); an edge across a face is
// counted by the leaf at its lower end when that end is active, else by the other.
std::size_t crossingTriangles(const openvdb::FloatGrid &grid, double isovalue) {
    using Tree = openvdb::FloatTree;
    using Leaf = Tree::LeafNodeType;
    std::vector<const Leaf *> leaves;
    grid.tree().getNodes(leaves);
    const float iso = float(isovalue);
    const auto count = [](std::uint64_t bits) { return std::size_t(__builtin_popcountll(bits)); };
    const std::size_t quads = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, leaves.size()), std::size_t(0),
        [&](const tbb::blocked_range<std::size_t> &r, std::size_t n) {
            openvdb::tree::ValueAccessor<const Tree> around(grid.tree());
            for (std::size_t l = r.begin(); l != r.end(); ++l) {
                const Leaf &leaf = *leaves[l];
                if (leaf.isEmpty()) continue;  // no active voxel: every edge it touches is the neighbours' or none
                LeafWords active;
                for (int x = 0; x < 8; ++x) active[x] = leaf.getValueMask().template getWord<std::uint64_t>(x);
                const LeafWords inside = insideBits(leaf, iso);
                // Inside the leaf: either end active, the ends on either side.
                for (int x = 0; x < 8; ++x) {
                    const std::uint64_t a = active[x], i = inside[x];
                    n += count((a | a >> 1) & (i ^ i >> 1) & kBelowTopZ);
                    n += count((a | a >> 8) & (i ^ i >> 8) & kBelowTopY);
                    if (x < 7) n += count((a | active[x + 1]) & (i ^ inside[x + 1]));
                }
                // Across the faces: from this leaf's active voxels upwards, and downwards where the lower end is not
                // active (else the lower leaf counted it).
                const openvdb::Coord &origin = leaf.origin();
                Neighbour up = neighbourBits(around, origin, 0, +1, iso);
                Neighbour down = neighbourBits(around, origin, 0, -1, iso);
                n += count(active[7] & (inside[7] ^ up.inside[0]));
                n += count(active[0] & ~down.active[7] & (inside[0] ^ down.inside[7]));
                up = neighbourBits(around, origin, 1, +1, iso), down = neighbourBits(around, origin, 1, -1, iso);
                for (int x = 0; x < 8; ++x) {
                    n += count(active[x] & (inside[x] ^ up.inside[x] << 56) & kTopY);
                    n += count(active[x] & ~(down.active[x] >> 56) & (inside[x] ^ down.inside[x] >> 56) & kBottomY);
                }
                up = neighbourBits(around, origin, 2, +1, iso), down = neighbourBits(around, origin, 2, -1, iso);
                for (int x = 0; x < 8; ++x) {
                    n += count(active[x] & (inside[x] ^ up.inside[x] << 7) & kTopZ);
                    n += count(active[x] & ~(down.active[x] >> 7) & (inside[x] ^ down.inside[x] >> 7) & kBottomZ);
                }
            }
            return n;
        },
        [](std::size_t a, std::size_t b) { return a + b; });
    return 2 * quads;
}

void validate(const openvdb::FloatGrid &surface, const SurfaceMeshSettings &settings) {
    if (!(settings.adaptivity >= 0.0 && settings.adaptivity <= 1.0))
        throw InvalidArgument("surface mesh adaptivity must be in [0, 1]");
    if (!(std::abs(settings.isovalue) <= 2.0 * surface.voxelSize()[0]))
        throw InvalidArgument("surface mesh isovalue must lie within 2 voxels of the surface");
    if (settings.maxTriangles != 0 && settings.maxTriangles < kMinTriangleBudget)
        throw InvalidArgument("surface mesh triangle budget must be 0 (none) or at least " +
                              std::to_string(kMinTriangleBudget));
    if (surface.getGridClass() != openvdb::GRID_LEVEL_SET)
        throw InvalidArgument("grid '" + surface.getName() + "' is not a level set");
    if (!surface.transform().isLinear() || !surface.hasUniformVoxels())
        throw InvalidArgument("grid '" + surface.getName() + "' needs a uniform linear transform");
}

int exponentOfTwo(int powerOfTwo) {
    int n = 0;
    while ((1 << n) < powerOfTwo) ++n;
    return n;
}

int powerOfTwoAtLeast(double x) {
    int f = 1;
    while (f < x && f < kMaxCoarsening) f *= 2;
    return f;
}

// The level set sampled at every `factor`-th voxel (factor a power of two), on voxels `factor` times larger with
// the same origin. Its values stay signed distances in m (clamped to the band's half-width, with the right
// sign, where the fine grid is inactive), so its zero crossing is the same surface, resolved to the coarse
// voxel. Every coarse voxel within one coarse voxel of a fine leaf is active: a closed shell around the
// surface, outside which a signed flood fill gives the inactive voxels their side. In parallel over the leaves.
openvdb::FloatGrid::Ptr coarsen(const openvdb::FloatGrid &fine, int factor) {
    using Tree = openvdb::FloatTree;
    const int shift = exponentOfTwo(factor);
    const double h = fine.voxelSize()[0];
    openvdb::FloatGrid::Ptr coarse = openvdb::FloatGrid::create(fine.background());
    openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(h * factor);
    xform->postTranslate(fine.transform().indexToWorld(openvdb::Vec3d(0.0)));
    coarse->setTransform(xform);
    coarse->setGridClass(openvdb::GRID_LEVEL_SET);
    std::vector<const Tree::LeafNodeType *> leaves;
    fine.tree().getNodes(leaves);
    tbb::enumerable_thread_specific<Tree> parts(Tree(fine.background()));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t> &r) {
        openvdb::tree::ValueAccessor<const Tree> in(fine.tree());
        openvdb::tree::ValueAccessor<Tree> out(parts.local());
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            if (leaves[i]->isEmpty()) continue;
            const openvdb::Coord lo = leaves[i]->origin(), hi = lo.offsetBy(Tree::LeafNodeType::DIM - 1);
            const openvdb::Coord from(lo.x() >> shift, lo.y() >> shift, lo.z() >> shift);
            const openvdb::Coord to(hi.x() >> shift, hi.y() >> shift, hi.z() >> shift);
            for (int x = from.x() - 1; x <= to.x() + 1; ++x)
                for (int y = from.y() - 1; y <= to.y() + 1; ++y)
                    for (int z = from.z() - 1; z <= to.z() + 1; ++z)
                        out.setValue(openvdb::Coord(x, y, z), in.getValue(openvdb::Coord(x, y, z) << shift));
        }
    });
    for (Tree &part : parts) coarse->tree().merge(part);
    openvdb::tools::signedFloodFill(coarse->tree());
    return coarse;
}

}  // namespace

SurfaceMesh meshSurface(const openvdb::FloatGrid &surface, const SurfaceMeshSettings &settings,
                        const SubProgress &progress) {
    initializeOpenVdb();
    validate(surface, settings);
    const std::size_t budget = settings.maxTriangles;
    const auto fits = [&](std::size_t triangles) { return budget == 0 || triangles <= budget; };
    progress.report(0.0);
    // A first guess of the coarsening, so large snow is not meshed at full resolution only to be thrown away:
    // a closed narrow band holds about 2 * halfWidth voxels per surface voxel, and volume-to-mesh makes about
    // two triangles per surface voxel; a factor f coarser has f^2 fewer.
    int factor = 1;
    if (budget != 0) {
        const double estimate = 2.0 * double(surface.activeVoxelCount()) / (2.0 * kHalfWidth);
        factor = std::max(1, powerOfTwoAtLeast(std::sqrt(estimate / double(budget))) / 2);
    }
    // The level set meshed at `factor` (1: the grid itself), kept from the last count.
    openvdb::FloatGrid::ConstPtr coarse;
    int coarseFactor = 1;
    const auto levelSet = [&](int f) -> const openvdb::FloatGrid & {
        if (f == 1) return surface;
        if (coarseFactor != f) coarse = coarsen(surface, f), coarseFactor = f;
        return *coarse;
    };
    // Without adaptivity the search counts triangles and meshes only the factor it ends at; with it, merging
    // decides the count, so each try is meshed.
    const bool counted = settings.adaptivity == 0.0 && budget != 0;
    SurfaceMesh best;
    std::size_t bestCount = 0;
    int bestFactor = factor;
    bool first = true;
    while (true) {
        progress.throwIfCancelled();
        SurfaceMesh next;
        if (!counted) next = mesh(levelSet(factor), settings.isovalue, settings.adaptivity);
        const std::size_t count =
            counted ? crossingTriangles(levelSet(factor), settings.isovalue) : next.triangles.size();
        const bool empty = count == 0 && !first;  // too coarse for the snow's thickness
        if (!empty && (first || count < bestCount)) {
            bestCount = count, bestFactor = factor;
            if (!counted) best = std::move(next);
        }
        first = false;
        if (empty || fits(bestCount) || factor >= kMaxCoarsening) break;
        // Triangles fall as the square of the voxel size.
        factor *= std::max(2, powerOfTwoAtLeast(std::sqrt(double(bestCount) / double(budget))));
        factor = std::min(factor, kMaxCoarsening);
        progress.report(0.5);
    }
    if (counted) best = mesh(levelSet(bestFactor), settings.isovalue, settings.adaptivity);
    progress.report(1.0);
    return best;
}

}  // namespace firn
