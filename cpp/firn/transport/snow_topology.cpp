#include "firn/transport/snow_topology.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <queue>

#include <glm/geometric.hpp>
#include <openvdb/tools/PoissonSolver.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/link_triangles.h"
#include "firn/util/threads.h"
#include "firn/util/work_check.h"

namespace firn {

namespace {

using IndexLeaf = openvdb::Int32Tree::LeafNodeType;

// Whether face f goes on flat past voxel i for `voxels` voxels inwards from its face g (each has f in air).
bool flatPast(const SnowTopology &topo, std::size_t i, int f, int g, int voxels) {
    for (int k = 0; k < voxels; ++k) {
        const std::int32_t next = topo.link[i][g ^ 1];
        if (next < 0 || !topo.isAirFace(std::size_t(next), f)) return false;
        i = std::size_t(next);
    }
    return true;
}

// Whether voxel i lies on a sharp edge or corner: two of its air faces at right angles, each going on flat
// for two voxels past the edge. Measured on bench/bake_suite.py: with one voxel, 30 % of a 5-voxel ball's
// surface voxels and the lumps' counted as edges (a voxel staircase makes such corners) and the lumps' bias
// went from -1 % to -11 %; with two, only the 5-voxel ball keeps a few (its flat caps), and a box and a
// slab keep all their edges. Or one face flat for three voxels and the other for one: a wall's vertical edge
// where a slope runs down to it (bumpy_plate's corner columns under the bumpy top, smooth with a normal blending
// the sunlit wall and the shadowed side, were as bright as the wall inside seen against the sun; mean 10.3 ->
// 10.0 %, every other case identical, docs/benchmarks.md plate-corner).
bool onSharpEdge(const SnowTopology &topo, std::size_t i) {
    for (int f = 0; f < 6; ++f)
        for (int g = f + 1; g < 6; ++g)
            if (f / 2 != g / 2 && topo.isAirFace(i, f) && topo.isAirFace(i, g) &&
                ((flatPast(topo, i, f, g, 2) && flatPast(topo, i, g, f, 2)) ||
                 (flatPast(topo, i, f, g, 3) && flatPast(topo, i, g, f, 1)) ||
                 (flatPast(topo, i, f, g, 1) && flatPast(topo, i, g, f, 3))))
                return true;
    return false;
}

// The longest terrace onTerrace walks (voxels): a plane tilted less than atan(1 / 16) = 3.6 degrees to the grid has
// longer ones, and its face's normal is as near the plane's.
constexpr int kTerraceVoxels = 16;

// Whether surface voxel i's air face f lies on a terrace of a voxel staircase: along one axis of its plane the face
// runs flat to a one-voxel step at both ends, down (the face goes on a voxel lower past it) or up (the next voxel's
// face is covered and the face goes on one voxel higher, or two where a thin voxel rides the step's edge). A plane
// tilted 5-20 degrees to the grid is such a staircase, its terraces flat past a voxel for 3 or more voxels along the
// slope and endlessly across it: onFlatWall took them for walls and gave their voxels the axis's normal, the full tilt
// off the plane (bench/oblique_plane_probe.py, 15 degrees, ball_grey's snow at phases 0, 0.23, 0.5: bake / Monte
// Carlo 1.06, 1.10, 1.03 -> 1.14, 1.13, 1.13; docs/benchmarks.md, wall-normal, lead-93). A layer's cut side runs up
// to its convex top edge and down to the ground or its own foot, no step.
bool onTerrace(const SnowTopology &topo, std::size_t i, int f) {
    const auto snow = [&](std::int32_t link) { return !SnowTopology::isFace(link); };
    // The last voxel of face f's flat run from i along face direction d, or nothing past kTerraceVoxels.
    const auto runEnd = [&](int d) -> std::optional<std::size_t> {
        std::size_t j = i;
        for (int k = 0; k < kTerraceVoxels; ++k) {
            const std::int32_t next = topo.link[j][d];
            if (!snow(next) || !topo.isAirFace(std::size_t(next), f)) return j;
            j = std::size_t(next);
        }
        return std::nullopt;
    };
    const auto stepDown = [&](std::size_t j, int d) {
        if (!topo.isAirFace(j, d)) return false;
        const std::int32_t under = topo.link[j][f ^ 1];
        if (!snow(under)) return false;
        const std::int32_t lower = topo.link[std::size_t(under)][d];
        return snow(lower) && topo.isAirFace(std::size_t(lower), f);
    };
    const auto stepUp = [&](std::size_t j, int d) {
        std::int32_t higher = topo.link[j][d];
        for (int k = 0; k < 2 && snow(higher); ++k) {
            higher = topo.link[std::size_t(higher)][f];
            if (snow(higher) && topo.isAirFace(std::size_t(higher), f)) return true;
        }
        return false;
    };
    const auto step = [&](std::size_t j, int d) { return stepDown(j, d) || stepUp(j, d); };
    for (int axis = 0; axis < 3; ++axis) {
        if (axis == f / 2) continue;
        const std::optional<std::size_t> lo = runEnd(2 * axis), hi = runEnd(2 * axis + 1);
        if (lo && hi && step(*lo, 2 * axis) && step(*hi, 2 * axis + 1)) return true;
    }
    return false;
}

// Whether surface voxel i's one air face lies on a flat wall: the face goes on flat for kFlatWallVoxels both ways
// along one axis of its plane and two voxels one way along the other (a layer's cut side below its top; not a
// ball's cap, whose flat faces reach 2-3 voxels at most). There the 3^3 gradient reads the partly filled voxel over
// the wall's top voxel and the air above it and tilted its normal 23-39 degrees up (bench/bake_suite.py's
// bumpy_plate, its cut sides under a top half a voxel over the voxel), where the trilinear density's surface stands
// within 14 degrees of the wall across that face: the tilted patch took the sky as a slope (more sky, less ground)
// and showed views from above its exit's peak (the shadowed wall over a black ground +24 %, docs/benchmarks.md,
// plate-valleys). Not a staircase's terrace (onTerrace), whose gradient follows its plane.
constexpr int kFlatWallVoxels = 4;

bool onFlatWall(const SnowTopology &topo, std::size_t i) {
    int f = 0;
    while (!topo.isAirFace(i, f)) ++f;
    const auto both = [&](int axis, int voxels) {
        return flatPast(topo, i, f, 2 * axis, voxels) && flatPast(topo, i, f, 2 * axis + 1, voxels);
    };
    const auto either = [&](int axis, int voxels) {
        return flatPast(topo, i, f, 2 * axis, voxels) || flatPast(topo, i, f, 2 * axis + 1, voxels);
    };
    const int a = (f / 2 + 1) % 3, b = (f / 2 + 2) % 3;
    return ((both(a, kFlatWallVoxels) && either(b, 2)) || (both(b, kFlatWallVoxels) && either(a, 2))) &&
           !onTerrace(topo, i, f);
}

// A fringe voxel in front of a surface voxel (no denser than it) weighs in its normal by (its density / the voxel's)^
// this: a fringe nearly as dense as the voxel holds the surface (the voxel lies a voxel under it, where the density
// hardly changes along the normal and the fringe's steps across it tilt the gradient), a thin one does not. Against
// the sphere's normal at the smooth surface voxels of bench/bake_suite.py's balls (mean / worst degrees;
// tests/cpp/transport/snow_topology_test.cpp): ball_grey (sigma_t h 5) 2.70 / 13.4 without it; exponent 0, 1, 2, 4,
// 8, 16: 2.54 / 5.7, 2.11 / 5.1, 1.76 / 4.5, 1.59 / 3.8, 1.56 / 3.4, 1.68 / 3.4; ball_issue (sigma_t h 10) 1.75 /
// 3.3 without, 3.18 / 5.3, 2.23 / 4.4, 1.66 / 3.8, 1.58 / 3.4, 1.72 / 3.3, 1.75 / 3.3; ball_snow 1.48 / 3.5 without,
// 1.32-2.13 / 3.5-4.0 with; ball_rgb's none (1.13 / 3.2). docs/benchmarks.md, grey-rims.
constexpr double kFringeNormalExponent = 8.0;

// Outward normal from the density gradient (a 3x3x3 Sobel stencil, plus each fringe voxel's in front by
// kFringeNormalExponent), or from the air faces where the gradient is flat or points the wrong way or the voxel's one
// air face lies on a flat wall (onFlatWall).
void computeSurfacePatches(const Medium &medium, SnowTopology &topo, const SubProgress &progress) {
    auto slot = std::make_shared<std::vector<std::int32_t>>(topo.size(), -1);
    std::int32_t surfaceVoxels = 0;
    for (std::size_t i = 0; i < topo.size(); ++i)
        for (int f = 0; f < 6; ++f)
            if (topo.isAirFace(i, f)) {
                (*slot)[i] = surfaceVoxels++;
                break;
            }
    topo.surfaceSlot = slot;
    topo.patches = SurfaceValues<SurfacePatch>(slot, std::size_t(surfaceVoxels));
    const double h = medium.voxelSize();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        Medium::Accessor density = medium.accessor();
        WorkCheck work(progress);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            work.add(WorkCheck::kVoxel);
            glm::dvec3 faces(0.0);
            int airFaces = 0;
            for (int f = 0; f < 6; ++f)
                if (topo.isAirFace(i, f)) faces += faceNormal(f), ++airFaces;
            if (airFaces == 0) continue;
            // Across an occluder face the stencil reads the voxel's own layer: the snow goes on to the occluder
            // and the emptiness beyond it is no air (it tilted a wall's lowest voxel 45° towards the ground).
            std::array<bool, 6> occluderFace{};
            for (int f = 0; f < 6; ++f)
                occluderFace[f] = SnowTopology::isFace(topo.link[i][f]) && !topo.isAirFace(i, f);
            const auto sobel = [&](const openvdb::Coord &c, const std::array<bool, 6> &occluder) {
                const auto step = [&](int d, int axis) { return d != 0 && occluder[2 * axis + (d > 0)] ? 0 : d; };
                glm::dvec3 gradient(0.0);
                for (int dx = -1; dx <= 1; ++dx)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dz = -1; dz <= 1; ++dz) {
                            const double w = (2 - std::abs(dx)) * (2 - std::abs(dy)) * (2 - std::abs(dz));
                            const double rho = density.getValue(c.offsetBy(step(dx, 0), step(dy, 1), step(dz, 2)));
                            gradient += w * rho * glm::dvec3(dx, dy, dz);
                        }
                return gradient;
            };
            const openvdb::Coord &c = topo.coord[i];
            glm::dvec3 gradient = sobel(c, occluderFace);
            for (int f = 0; f < 6; ++f) {
                const double fringe = topo.isAirFace(i, f) ? density.getValue(c + faceStep(f)) / topo.density[i] : 0.0;
                if (fringe <= 0.0 || fringe > 1.0) continue;  // a denser voxel outside is another surface's fringe
                // The fringe shares the voxel's occluder faces (a locally flat occluder goes on past it) but for
                // the one behind the voxel: a fringe above a voxel on the ground reads the voxel under it.
                std::array<bool, 6> fringeOccluder = occluderFace;
                fringeOccluder[f ^ 1] = false;
                gradient += std::pow(fringe, kFringeNormalExponent) * sobel(c + faceStep(f), fringeOccluder);
            }
            glm::dvec3 n = -gradient;
            if (glm::length(n) <= 1e-6 * topo.density[i] || glm::dot(n, faces) < 0.0) n = faces;
            // A wall's one air face takes its own normal (onFlatWall).
            if (airFaces == 1 && onFlatWall(topo, i)) n = faces;
            SurfacePatch &patch = topo.patches.surface(i);
            patch.normal = glm::length(n) > 0.0 ? glm::normalize(n) : glm::dvec3(0.0, 0.0, 1.0);
            patch.sharp = onSharpEdge(topo, i);
            if (patch.sharp) {
                for (int f = 0; f < 6; ++f)
                    if (topo.isAirFace(i, f)) patch.share[f] = 1.0f / float(airFaces);
                patch.area = h * h * airFaces;
                continue;
            }
            double projected = 0.0;
            for (int f = 0; f < 6; ++f)
                if (topo.isAirFace(i, f)) projected += std::max(0.0, glm::dot(patch.normal, faceNormal(f)));
            for (int f = 0; f < 6; ++f)
                if (topo.isAirFace(i, f))
                    patch.share[f] = float(projected > 1e-6 ? std::max(0.0, glm::dot(patch.normal, faceNormal(f))) / projected
                                                           : 1.0 / airFaces);
            patch.area = h * h * std::max(projected, 0.3);
        }
    });
}

// Snow (kg/m^2) from voxel c's centre out through face `face` to where the density ramps to zero, through
// any fringe voxels: the trapezoid rule is exact for the linear ramps between voxel centres.
float rampMass(const Medium &medium, Medium::Accessor &density, const openvdb::Coord &c, int face) {
    double mass = 0.0, inner = density.getValue(c);
    openvdb::Coord next = c;
    for (int k = 0; k < 4 && inner > 0.0; ++k) {
        next += faceStep(face);
        const double outer = density.getValue(next);
        mass += 0.5 * medium.voxelSize() * (inner + outer);
        inner = outer;
    }
    return float(mass);
}

// SurfacePatch::curvature of surface voxel j, from its block's patches' normals.
double curvatureAround(const SnowTopology &topo, std::size_t j,
                       openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index) {
    const openvdb::Coord &cj = topo.coord[j];
    const glm::dvec3 n = topo.patches[j].normal;
    std::array<std::pair<glm::dvec3, glm::dvec3>, 27> near;  // offsets (voxels) and normals
    std::array<double, 27> weight{};
    int count = 0;
    glm::dvec3 mean(0.0);
    double total = 0.0;
    for (int k = 0; k < 27; ++k) {
        const openvdb::Coord d = blockOffset(k);
        const std::int32_t i = index.getValue(cj + d);
        if (i < 0 || !topo.patches[std::size_t(i)].isSurface()) continue;
        const double w = glm::dot(n, topo.patches[std::size_t(i)].normal);
        if (w <= 0.0) continue;
        near[count] = {glm::dvec3(d.x(), d.y(), d.z()), topo.patches[std::size_t(i)].normal}, weight[count++] = w;
        mean += w * glm::dvec3(d.x(), d.y(), d.z()), total += w;
    }
    if (total <= 0.0) return 0.0;
    mean /= total;
    double bending = 0.0, spread = 0.0;
    for (int k = 0; k < count; ++k) {
        const glm::dvec3 p = near[k].first - mean, t = p - glm::dot(p, n) * n;
        bending += weight[k] * glm::dot(near[k].second, t), spread += weight[k] * glm::dot(t, t);
    }
    return spread > 1e-6 ? bending / spread : 0.0;
}

// Every surface patch's curvature, once its block's normals are all known: the light's skin ring, each pass's
// surface light and the grids' ramps read it (it was worked out again for each).
void computeCurvatures(SnowTopology &topo, const SubProgress &progress) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 4096), [&](const auto &range) {
        WorkCheck work(progress);
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            work.add(WorkCheck::kVoxel);
            if (topo.patches[i].isSurface())
                topo.patches.surface(i).curvature = curvatureAround(topo, i, index);
        }
    });
}

// A block's lists in one vector (a vector per unknown took 65 MB and 2.5 M allocations on the car sample).
void computeNeighbourhoods(SnowTopology &topo, const SubProgress &progress) {
    constexpr std::size_t kBlock = 4096;
    topo.neighbourhoodStart.assign(topo.size() + 1, 0);
    std::vector<std::vector<std::uint32_t>> lists((topo.size() + kBlock - 1) / kBlock);  // per block, in order
    tbb::parallel_for(std::size_t(0), lists.size(), [&](std::size_t b) {
        WorkCheck work(progress);
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        for (std::size_t i = b * kBlock; i < std::min(topo.size(), (b + 1) * kBlock); ++i) {
            work.add(WorkCheck::kVoxel);
            if (!topo.patches[i].isSurface()) continue;
            const std::size_t before = lists[b].size();
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const std::int32_t j = index.getValue(topo.coord[i].offsetBy(dx, dy, dz));
                        if (j >= 0 && topo.patches[j].isSurface()) lists[b].push_back(std::uint32_t(j));
                    }
            topo.neighbourhoodStart[i + 1] = std::uint32_t(lists[b].size() - before);  // the count, summed below
        }
    });
    for (std::size_t i = 0; i < topo.size(); ++i) topo.neighbourhoodStart[i + 1] += topo.neighbourhoodStart[i];
    topo.neighbourhood.reserve(topo.neighbourhoodStart.back());
    for (const auto &list : lists) topo.neighbourhood.insert(topo.neighbourhood.end(), list.begin(), list.end());
}

// Optical depth (sigma_t) from outside to each voxel centre near the surface by Dijkstra from the surface
// voxels inwards, over the shell only.
void computeShell(const Medium &medium, SnowTopology &topo, int shellVoxels, const SubProgress &progress) {
    constexpr double kShellStart = 3.0, kShellEnd = 6.0;
    const double k = medium.optics().extinctionPerDensity, h = medium.voxelSize();
    std::vector<double> depth(topo.size(), std::numeric_limits<double>::infinity());
    parallelAssign(topo.shellOwner, topo.size(), std::int32_t(-1));
    parallelAssign(topo.shellWeight, topo.size(), 0.0f);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        Medium::ColumnMarcher marcher(medium);
        WorkCheck work(progress);
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            if (topo.patches[i].isSurface()) {
                work.add(WorkCheck::kVoxel);
                depth[i] = k * marcher.column(medium.voxelCentre(topo.coord[i]), topo.patches[i].normal, 3.0 * h, kShellEnd / k);
                topo.shellOwner[i] = std::int32_t(i);
                topo.shellWeight[i] = 1.0f;
            }
    });
    using Entry = std::pair<double, std::int32_t>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    for (std::size_t i = 0; i < topo.size(); ++i)  // only shallow surface voxels have a shell to fill
        if (topo.patches[i].isSurface() && depth[i] < kShellEnd) queue.emplace(depth[i], std::int32_t(i));
    WorkCheck work(progress);
    while (!queue.empty()) {
        work.add(WorkCheck::kVoxel);
        const auto [d, i] = queue.top();
        queue.pop();
        if (d > depth[i]) continue;
        for (int f = 0; f < 6; ++f) {
            const std::int32_t j = topo.link[i][f];
            if (j < 0 || topo.patches[j].isSurface()) continue;
            const double next = d + 0.5 * k * h * (topo.density[i] + topo.density[j]);
            if (next >= kShellEnd || next >= depth[j]) continue;
            depth[j] = next, topo.shellOwner[j] = topo.shellOwner[i];
            topo.shellWeight[j] = float(std::clamp((kShellEnd - next) / (kShellEnd - kShellStart), 0.0, 1.0));
            queue.emplace(next, j);
        }
    }
    // The first shellVoxels - 1 voxels under the surface, whatever their optical depth.
    std::vector<std::int32_t> frontier;
    for (std::size_t i = 0; i < topo.size(); ++i)
        if (topo.patches[i].isSurface()) frontier.push_back(std::int32_t(i));
    std::vector<std::uint8_t> reached(topo.size(), 0);
    for (int step = 1; step < shellVoxels; ++step) {
        std::vector<std::int32_t> next;
        for (const std::int32_t i : frontier)
            for (int f = 0; f < 6; ++f) {
                const std::int32_t j = topo.link[i][f];
                if (j < 0 || topo.patches[j].isSurface() || reached[j]) continue;
                reached[j] = 1;
                if (topo.shellWeight[j] < 1.0f) topo.shellOwner[j] = topo.shellOwner[i], topo.shellWeight[j] = 1.0f;
                next.push_back(j);
            }
        frontier = std::move(next);
    }
}

}  // namespace

std::optional<RayCaster::Hit> occluderOnLink(const Medium &medium, const Occluders &occluders,
                                             const openvdb::Coord &lower, int axis) {
    const double h = medium.voxelSize();
    glm::dvec3 up(0.0);
    up[axis] = 1.0;
    return occluders.caster().intersect(glm::vec3(medium.voxelCentre(lower) + kLinkRayNudge * h * up), glm::vec3(up),
                                        0.0f, float(h));
}

SnowTopology buildSnowTopology(const Medium &medium, const Occluders &occluders, const SubProgress &progress,
                               int shellVoxels) {
    const double h = medium.voxelSize();
    const float minDensity = float(kMinVoxelOpticalDepth / (medium.optics().extinctionPerDensity * h));
    const openvdb::FloatTree &densityTree = medium.density().tree();

    openvdb::BoolTree dense(densityTree, false, openvdb::TopologyCopy());
    openvdb::tree::LeafManager<openvdb::BoolTree>(dense).foreach([&](openvdb::BoolTree::LeafNodeType &leaf, std::size_t) {
        const auto *densityLeaf = densityTree.probeConstLeaf(leaf.origin());
        for (auto it = leaf.beginValueOn(); it; ++it)
            if (!densityLeaf || densityLeaf->getValue(it.pos()) < minDensity) it.setValueOff();
    });
    // Peel surface fringes: thin voxels with air on one side and a thick voxel on the other.
    const float fringeDensity = float(kFringeOpticalDepth / (medium.optics().extinctionPerDensity * h));
    openvdb::BoolTree mask(dense);
    openvdb::tree::LeafManager<openvdb::BoolTree>(mask).foreach([&](openvdb::BoolTree::LeafNodeType &leaf, std::size_t) {
        openvdb::tree::ValueAccessor<const openvdb::BoolTree> isDense(dense);
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> density(densityTree);
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            if (density.getValue(c) >= fringeDensity) continue;
            for (int f = 0; f < 6; ++f)
                if (!isDense.isValueOn(c + faceStep(f)) && density.getValue(c - faceStep(f)) >= fringeDensity) {
                    it.setValueOff();
                    break;
                }
        }
    });
    SnowTopology topo;
    topo.index = openvdb::tools::poisson::createIndexTree(mask);
    const std::size_t n = std::size_t(topo.index->activeVoxelCount());
    topo.coord.resize(n), topo.density.resize(n), topo.link.resize(n);
    progress.report(0.2);

    openvdb::tree::LeafManager<openvdb::Int32Tree> leaves(*topo.index);
    const double linkPad = firn::linkPad(medium, occluders);
    progress.report(0.4);
    progress.throwIfCancelled();

    // Links and boundary faces, leaf by leaf; faces are numbered in leaf order afterwards.
    std::vector<std::vector<BoundaryFace>> leafFaces(leaves.leafCount());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        WorkCheck work(progress);
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        Medium::Accessor density = medium.accessor();
        // The occluder hit up each axis from each voxel of the leaf (by offset), taken over by the voxel above
        // where both lie in the leaf: the car's topology cast a ray per face of every voxel near an occluder.
        std::vector<std::optional<RayCaster::Hit>> upHits(3 * IndexLeaf::SIZE);
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            const IndexLeaf &leaf = leaves.leaf(l);
            // The links' lower voxels: the leaf's own and the ones below its lower faces. A leaf no triangle comes
            // near (one Embree box query) casts no ray.
            const openvdb::CoordBBox lowers(leaf.origin() - openvdb::Coord(1), leaf.origin() + openvdb::Coord(7));
            const LinkTriangles linkTriangles(medium, occluders, lowers, linkPad);
            const bool nearTriangles = !linkTriangles.empty();
            const auto *densityLeaf = densityTree.probeConstLeaf(leaf.origin());
            for (auto it = leaf.cbeginValueOn(); it; ++it) {
                work.add(WorkCheck::kVoxel);
                const std::uint32_t i = std::uint32_t(*it);
                const openvdb::Coord c = it.getCoord();
                topo.coord[i] = c;
                topo.density[i] = densityLeaf->getValue(it.pos());
                for (int f = 0; f < 6; ++f) {
                    BoundaryFace face{i, std::uint8_t(f), false, 0.0f, 0};
                    if (nearTriangles) {
                        // Voxels come in offset order: the one below in the same leaf has tested its link up.
                        const bool up = f & 1;
                        const openvdb::Coord lower = up ? c : c + faceStep(f);
                        const double nudge = kLinkRayNudge * h;
                        const openvdb::Index lowerOffset = IndexLeaf::coordToOffset(lower);
                        std::optional<RayCaster::Hit> hit;
                        if (!up && (c[f / 2] & 7) != 0 && leaf.isValueOn(lowerOffset))
                            hit = upHits[3 * lowerOffset + f / 2];
                        else if (linkTriangles.mayCross(lower, f / 2))
                            hit = occluderOnLink(medium, occluders, lower, f / 2);
                        if (up) upHits[3 * lowerOffset + f / 2] = hit;
                        if (hit) {
                            face.occluder = true, face.triangle = hit->triangle;
                            face.distance = float(std::clamp(up ? hit->distance + nudge : h - hit->distance - nudge, 0.0, h));
                        }
                    }
                    const std::int32_t neighbour = index.getValue(c + faceStep(f));
                    if (!face.occluder && neighbour >= 0) {
                        topo.link[i][f] = neighbour;
                    } else {
                        if (!face.occluder) face.rampMass = rampMass(medium, density, c, f);
                        topo.link[i][f] = -1 - std::int32_t(leafFaces[l].size());
                        leafFaces[l].push_back(face);
                    }
                }
            }
        }
    });
    std::vector<std::size_t> offset(leaves.leafCount() + 1, 0);
    for (std::size_t l = 0; l < leaves.leafCount(); ++l) offset[l + 1] = offset[l] + leafFaces[l].size();
    topo.faces.resize(offset.back());
    tbb::parallel_for(std::size_t(0), leaves.leafCount(), [&](std::size_t l) {
        std::copy(leafFaces[l].begin(), leafFaces[l].end(), topo.faces.begin() + offset[l]);
        for (const BoundaryFace &face : leafFaces[l]) {
            std::int32_t &link = topo.link[face.voxel][face.face];
            link = -1 - std::int32_t(offset[l] + SnowTopology::faceIndex(link));
        }
    });
    computeSurfacePatches(medium, topo, progress);
    // The shell's Dijkstra runs on one thread: the neighbourhoods and curvatures (parallel loops) run beside it. They
    // write apart (the shell's owners and weights; the neighbourhood lists and the patches' curvatures) and read what
    // the patches and links already hold.
    runBeside([&] { computeNeighbourhoods(topo, progress), computeCurvatures(topo, progress); },
              [&] { computeShell(medium, topo, shellVoxels, progress); });
    progress.report(1.0);
    return topo;
}

double surfaceCurvature(const SnowTopology &topo, const openvdb::Coord &cj,
                        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index) {
    const std::int32_t j = index.getValue(cj);
    return j < 0 ? 0.0 : topo.patches[std::size_t(j)].curvature;  // an inner voxel's patch: 0
}

}  // namespace firn
