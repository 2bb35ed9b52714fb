#include "firn/transport/bake_grid_values.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <openvdb/tools/Morphology.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/edge_lobe.h"
#include "firn/transport/incident_light.h"
#include "firn/transport/limb_carry.h"
#include "firn/transport/skin_ring.h"
#include "firn/transport/sun_lobe.h"
#include "firn/util/sampling.h"
#include "firn/util/version.h"
#include "firn/util/work_check.h"

namespace firn::bake {

namespace {

// What traced voxel n shows a neighbour at `offset`: the mean of its lit faces that face it (FaceSources::lit),
// else `own`, its mean. A face's source is unbiased where the voxel's moments fit reads the sun-lit views 4 % dark
// at 256 paths (docs/benchmarks.md, spray-air); its unlit faces, taken too, put the rims up (spray-lit-faces).
Source litFacesToward(const openvdb::Coord &n, const openvdb::Coord &offset, TracedIndex &tracedIndex,
                      const MonteCarloVoxels &traced, const Source &own) {
    const std::int32_t t = tracedIndex.getValue(n);
    if (t < 0 || traced.faces.empty() || traced.facesAt[t] < 0) return own;
    const FaceSources &faces = traced.faces[traced.facesAt[t]];
    Source sum;
    int count = 0;
    for (int a = 0; a < 3; ++a) {
        if (offset[a] == 0) continue;
        const int f = 2 * a + (offset[a] > 0);
        if (faces.open >> f & faces.lit >> f & 1u) sum.add(faces.source[f]), ++count;
    }
    if (!count) return own;
    sum.divideBy(float(count));
    return sum;
}

// What a surface voxel shows a neighbour, and of its peaked lobe, the share its faces towards that neighbour hold
// (1: all of it, where it shows one lobe over all its faces).
struct ShownToward {
    Source source;
    float peakShare = 1.0f;
};

// What sharp edge voxel j (not traced) shows a neighbour at `offset`: the mean of its flat air faces' own lobes that
// face it (EdgeFaceLobes) and, of its peaked lobe, those faces' share (EdgeFaceLobes::Voxel::peakShare), else `own`,
// its one lobe over all its faces (share 1).
ShownToward ownFacesToward(const EdgeFaceLobes &edgeFaces, std::size_t j, const openvdb::Coord &offset,
                           const Source &own) {
    const EdgeFaceLobes::Voxel *faces = edgeFaces.find(j);
    if (!faces) return {own};
    Source sum;
    int count = 0;
    float share = 0.0f;
    std::array<int, 3> flat{};  // the faces towards the neighbour
    for (int a = 0; a < 3; ++a) {
        if (offset[a] == 0) continue;
        const int f = 2 * a + (offset[a] > 0);
        if (faces->flat >> f & 1u)
            sum.l0 += faces->lobe[f].l0, sum.l1 += faces->lobe[f].l1, share += faces->peakShare[f], flat[count++] = f;
    }
    if (!count) return {own};
    Source S = own;
    S.l0 = sum.l0, S.l1 = sum.l1;
    if (count > 1) {  // diagonal to the edge: beyond all of those faces (lobeBeyondFaces)
        FaceLobes beyond;
        beyond.count = std::size_t(count);
        for (int c = 0; c < 3; ++c) {
            for (int q = 0; q < count; ++q) {
                const BroadLobe &face = faces->lobe[flat[q]];
                beyond.face[q] = {faceNormal(flat[q]), face.l0[c], glm::dvec3(face.l1[c])};
            }
            const SourceLobe lobe = lobeBeyondFaces(beyond);
            S.l0[c] = float(lobe.l0), S.l1[c] = glm::vec3(lobe.l1);
        }
    }
    S.peak0 *= share, S.peak1 *= share;
    return {S, share};
}

// The radiance the surface voxels around voxel c (outside the snow) show towards it: their values
// weighted by how much their surface faces c (a voxel beside an edge takes the side's, one above it the
// top's), and their normals so weighted (`facing`, unit; zero where none faces c). False if no surface voxel is
// near. `carrier`: the surface voxel facing c most (the first in blockOffset's order among equals), where one does.
// rampPart: of S's peaked lobe, the part the beams the ramp scatters itself hold (SourceValues::rampPeaks), so
// weighted.
bool facingAverage(const SnowTopology &topo, const openvdb::Coord &c,
                   openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, const SourceValues &source,
                   TracedIndex &tracedIndex, const MonteCarloVoxels &traced, Source &S, Source &rampPart,
                   glm::dvec3 &facing, openvdb::Coord &carrier) {
    double total = 0.0, most = 0.0;
    int count = 0, mostAt = 27;
    glm::dvec3 l0(0.0), peak0(0.0), peak1(0.0), ramp0(0.0), ramp1(0.0), normal(0.0);
    glm::dmat3 l1(0.0);
    const auto addRampPart = [&](const openvdb::Coord &n, std::int32_t j, double w) {  // not a traced voxel's
        if (tracedIndex.getValue(n) >= 0) return;
        const Source r = source.rampPeaks.with(BroadLobe{}, std::size_t(j));
        ramp0 += w * glm::dvec3(r.peak0), ramp1 += w * glm::dvec3(r.peak1);
    };
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
                const openvdb::Coord n = c.offsetBy(-dx, -dy, -dz);
                const std::int32_t j = index.getValue(n);
                if (j < 0 || !topo.patches[j].isSurface()) continue;
                const double w =
                    std::max(0.0, glm::dot(topo.patches[j].normal, glm::normalize(glm::dvec3(dx, dy, dz))));
                const int k = (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1);  // blockOffset(k): (dx, dy, dz)
                if (w > most || (w == most && w > 0.0 && k < mostAt))
                    most = w, mostAt = k, carrier = n;
                ++count;
                // Not facing c (w 0), it adds nothing but its count: its values are not read (each a cache miss).
                if (w == 0.0) continue;
                const auto [v, peakShare] =
                    topo.patches[j].sharp && tracedIndex.getValue(n) < 0
                        ? ownFacesToward(source.edgeFaces, std::size_t(j), {dx, dy, dz}, source[j])
                        : ShownToward{litFacesToward(n, {dx, dy, dz}, tracedIndex, traced, source[j])};
                l0 += w * glm::dvec3(v.l0), l1 += w * glm::dmat3(v.l1);
                peak0 += w * glm::dvec3(v.peak0), peak1 += w * glm::dvec3(v.peak1);
                addRampPart(n, j, w * peakShare);  // of j's peaked lobe, its faces' to c
                normal += w * topo.patches[j].normal;
                total += w;
            }
    if (count == 0) return false;
    facing = glm::length(normal) > 0.0 ? glm::normalize(normal) : normal;
    if (total <= 0.0) {  // nothing faces c: plain average
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const std::int32_t j = index.getValue(c.offsetBy(dx, dy, dz));
                    if (j < 0 || !topo.patches[j].isSurface()) continue;
                    const Source v = source[j];
                    l0 += glm::dvec3(v.l0), l1 += glm::dmat3(v.l1), total += 1.0;
                    peak0 += glm::dvec3(v.peak0), peak1 += glm::dvec3(v.peak1);
                    addRampPart(c.offsetBy(dx, dy, dz), j, 1.0);
                }
    }
    S.l0 = glm::vec3(l0 / total);
    S.l1 = glm::mat3(l1 / total);
    S.peak0 = glm::vec3(peak0 / total), S.peak1 = glm::vec3(peak1 / total);
    rampPart.peak0 = glm::vec3(ramp0 / total), rampPart.peak1 = glm::vec3(ramp1 / total);
    return true;
}

// Traced voxel t's grid value: what it shows its faces' cameras where it has face sources, else its source.
const Source &ownValue(const MonteCarloVoxels &traced, std::int32_t t) {
    return !traced.faces.empty() && traced.facesAt[t] >= 0 ? traced.faces[traced.facesAt[t]].shown : traced.source[t];
}

// What air voxel c carries of its face neighbours' face sources (MonteCarloVoxels::faces) towards it, averaged;
// false where none holds one.
bool faceCarried(const openvdb::Coord &c, TracedIndex &tracedIndex, const MonteCarloVoxels &traced, Source &S) {
    if (traced.faces.empty()) return false;
    Source sum;
    int count = 0;
    for (int f = 0; f < 6; ++f) {
        openvdb::Coord n = c;
        n[f / 2] -= f % 2 ? 1 : -1;  // the neighbour whose face f is c's
        const std::int32_t t = tracedIndex.getValue(n);
        if (t < 0 || traced.facesAt[t] < 0 || !(traced.faces[traced.facesAt[t]].open >> f & 1u)) continue;
        const Source &v = traced.faces[traced.facesAt[t]].source[f];
        sum.add(v), ++count;
    }
    if (!count) return false;
    sum.divideBy(float(count));
    S = sum;
    return true;
}

// at: the voxels with values -> their place in `values` (by leaf of `leaves`), with leaves only where values are
// (over all the grids' leaves it took 17 bytes per unknown on the car).
void placeValues(const LeafValues &values, const openvdb::tree::LeafManager<const openvdb::BoolTree> &leaves,
                 openvdb::Int32Tree &at) {
    for (std::size_t l = 0; l < leaves.leafCount(); ++l)
        if (!values.emptyIn(l)) at.touchLeaf(leaves.leaf(l).origin());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            if (values.emptyIn(l)) continue;
            openvdb::Int32Tree::LeafNodeType &leaf = *at.probeLeaf(leaves.leaf(l).origin());
            values.forEachIn(l, [&](std::size_t k) { leaf.setValueOnly(values.values[k].offset, std::int32_t(k)); });
        }
    });
}

// Whether voxel c is a corner of a cell where the trilinear density can be non-zero: elsewhere the gathering
// reads no value (bakedRadianceAlong skips samples without snow).
bool besideSnow(Medium::Accessor &density, const openvdb::Coord &c) {
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz)
                if (density.getValue(c.offsetBy(dx, dy, dz)) > 0.0f) return true;
    return false;
}

// The grids' values (BakedGrids::Values) of a source function.
BakedGrids::Values sourceComponents(const Source &S) {
    BakedGrids::Values out;
    for (int k = 0; k < int(BakedGrids::kCount); ++k) out[k] = sourceComponent(S, k);
    return out;
}

// The on-states of a voxel mask within `radius` (at most 4) of voxel c, read from the at most eight leaves that
// hold them (found once) instead of looked up voxel by voxel.
class BlockMask {
  public:
    BlockMask(openvdb::tree::ValueAccessor<const openvdb::BoolTree> &mask, const openvdb::Coord &c, int radius)
        : split_(((c.x() - radius) & ~7) + 8, ((c.y() - radius) & ~7) + 8, ((c.z() - radius) & ~7) + 8) {
        for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b)
                for (int d = 0; d < 2; ++d)
                    leaves_[a][b][d] = mask.probeConstLeaf(split_.offsetBy(8 * a - 8, 8 * b - 8, 8 * d - 8));
    }
    bool isOn(const openvdb::Coord &v) const {  // v within the radius of c
        const openvdb::BoolTree::LeafNodeType *leaf =
            leaves_[v.x() >= split_.x()][v.y() >= split_.y()][v.z() >= split_.z()];
        return leaf && leaf->isValueOn(v);
    }

  private:
    openvdb::Coord split_;  // the upper leaves' origin
    const openvdb::BoolTree::LeafNodeType *leaves_[2][2][2];
};

// The suns' uncollided transmittance through the snow at the points of a quarter-voxel lattice (index space: odd
// multiples of 1/4), each point marched once: the 4^3 points beamsInRamp averages over a voxel's hat are shared with
// its neighbours' (a point at c + 1/4 is also c + 1 - 3/4), so a band of ramp voxels marches a few times fewer
// columns. One per thread, holding one leaf's points at a time in a dense array (18^3 a sun for the dilated
// topology's 8^3 leaves) whose stamps say which hold this leaf's value: no hash map to fill and clear per leaf.
class QuarterPointSun {
  public:
    QuarterPointSun(const Medium &medium, std::size_t suns)
        : medium_(medium), marcher_(medium), known_(suns * kPerSun), stamp_(suns * kPerSun, 0) {}
    // Starts the points of the 8^3 leaf at origin: none known.
    void startLeaf(const openvdb::Coord &origin) {
        first_ = openvdb::Coord(4 * origin.x() - 3, 4 * origin.y() - 3, 4 * origin.z() - 3);
        ++leaf_;
    }
    // Sun b's transmittance at index-space point q / 4 (q odd per axis, about a voxel of the leaf).
    double at(std::size_t b, const glm::dvec3 &direction, const openvdb::Coord &q) {
        const int x = (q.x() - first_.x()) / 2, y = (q.y() - first_.y()) / 2, z = (q.z() - first_.z()) / 2;
        const std::size_t i = b * kPerSun + std::size_t((x * kPerAxis + y) * kPerAxis + z);
        if (stamp_[i] != leaf_) {
            const double perColumn = medium_.optics().extinctionPerDensity;  // m^2/kg: uncollided
            const double limit = std::log(1e5) / perColumn;  // kg/m^2: the transmittance below 1e-5
            const double column = marcher_.column(medium_.indexToWorld(glm::dvec3(q.x(), q.y(), q.z()) / 4.0),
                                                  direction, std::numeric_limits<double>::infinity(), limit);
            known_[i] = column < limit ? std::exp(-perColumn * column) : 0.0;
            stamp_[i] = leaf_;
        }
        return known_[i];
    }

  private:
    // Odd quarters from -3/4 before a leaf's first voxel to 3/4 past its last.
    static constexpr int kPerAxis = 2 * int(openvdb::BoolTree::LeafNodeType::DIM) + 2;
    static constexpr std::size_t kPerSun = std::size_t(kPerAxis) * kPerAxis * kPerAxis;
    const Medium &medium_;
    Medium::ColumnMarcher marcher_;
    std::vector<double> known_;         // per sun, then point
    std::vector<std::uint64_t> stamp_;  // the leaf (leaf_) whose value known_ holds
    openvdb::Coord first_;              // the leaf's lowest point, in quarters
    std::uint64_t leaf_ = 0;            // leaves started
};

// The mean of f over ramp voxel c's trilinear hat weighted by the density (what the renderer's emission weighs), on
// 4^3 points at odd quarters from c's centre (index space, f given each point times 4); zero where c's hat holds no
// snow.
template <typename T, typename F>
T hatAverage(const openvdb::Coord &c, Medium::ColumnMarcher &marcher, const F &f) {
    constexpr int kPoints[4] = {-3, -1, 1, 3};  // quarter voxels from c's centre, per axis
    const auto point = [&](int k) {  // point k, x fastest
        return openvdb::Coord(4 * c.x() + kPoints[k % 4], 4 * c.y() + kPoints[k / 4 % 4], 4 * c.z() + kPoints[k / 16]);
    };
    // The density at the points read cell by cell: the hat's 8 cells hold 2^3 points each, and the sampler reads a
    // cell's eight corners again each time the walk re-enters it (in the points' order, 32 times a hat, not 8).
    // Along each axis a point's index is 2 (its cell's bit) + (its bit within the cell).
    const auto along = [](int cell, int n, int axis) { return 2 * (cell >> axis & 1) + (n >> axis & 1); };
    std::array<double, 64> density;
    for (int cell = 0; cell < 8; ++cell)
        for (int n = 0; n < 8; ++n) {
            const int k = along(cell, n, 0) + 4 * along(cell, n, 1) + 16 * along(cell, n, 2);
            const openvdb::Coord q = point(k);
            density[k] = marcher.densityAt(openvdb::Vec3d(q.x(), q.y(), q.z()) / 4.0);
        }
    T sum(0.0);
    double weights = 0.0;
    for (int k = 0; k < 64; ++k) {
        const openvdb::Coord q = point(k);
        const double w = (4 - std::abs(kPoints[k % 4])) * (4 - std::abs(kPoints[k / 4 % 4])) *
                         (4 - std::abs(kPoints[k / 16])) * density[k];
        if (w <= 0.0) continue;
        sum += w * f(q);
        weights += w;
    }
    return weights > 0.0 ? sum / weights : T(0.0);
}

// Whether the occluders hide the way `towards` (unit) from p: the one shadow ray a ramp voxel's centre casts for a sun
// or a sky direction before its hat's marches.
bool occludersHide(const Scene &scene, const glm::dvec3 &p, const glm::dvec3 &towards) {
    return !scene.occluders->empty() && scene.occluders->caster().occluded(glm::vec3(p), glm::vec3(towards), 1e-5f);
}

// Sun b's transmittance through the snow raised to `power` (1: uncollided; 1 - f: delta-scaled, Crossing::Uncollided's
// exponent scaled), averaged over voxel c's trilinear hat weighted by the density: what the renderer's emission at c
// weighs (4^3 points). Zero where the hat holds no snow. Not T at c's centre: an air voxel just outside a limb has
// T = 1 there and shadowed snow in its hat (ball_grey's equator rims seen against the sun read +200 to +270 % with
// beamsInRamp's T at the centre, +49 % with forwardPeakThrough's; docs/benchmarks.md, ball-rims, grey-rims-53).
double hatSunTransmittance(const openvdb::Coord &c, std::size_t b, const glm::dvec3 &direction, double power,
                           Medium::ColumnMarcher &marcher, QuarterPointSun &sunAt) {
    return hatAverage<double>(c, marcher, [&](const openvdb::Coord &q) {
        const double T = sunAt.at(b, direction, q);
        return power == 1.0 ? T : std::pow(T, power);
    });
}

// The share of a peak leaving the voxel centred at `from` that crosses the ramp on to c's centre `to` in the
// forward beam: the delta-scaled transmittance (1 - forwardKept of the extinction) from the boundary of the two
// voxels, halfway (the peak is its voxel's surface radiance: its own snow is behind it).
double rampCrossing(const Medium &medium, const glm::dvec3 &from, const glm::dvec3 &to, double forwardKept,
                    Medium::ColumnMarcher &marcher) {
    const glm::dvec3 way = to - from;
    const double length = glm::length(way);  // m
    const double column = marcher.column(from + 0.5 * way, way / length, 0.5 * length,
                                         std::numeric_limits<double>::infinity());  // kg/m^2
    return std::exp(-(1.0 - forwardKept) * medium.optics().extinctionPerDensity * column);
}

// Carriers facing a sun below this cosine (well past the terminator) weigh the peaks forwardPeakThrough carries by
// the sun's delta-scaled transmittance averaged over c's hat (hatSunTransmittance), not at c's centre: there an air
// voxel beside the limb has T = 1 at its centre and the body's shadow in its hat (ball_grey's equator rims seen
// against the sun +49 -> +25 %, mean 8.0 -> 7.4 %). Nearer the terminator the centre's T stands in for the multiply
// forward-scattered sun the rims lack (docs/benchmarks.md, rim-forward): averaged from -0.2 up, ball_issue's view
// against the sun -13 -> -14 %, at 0 ball_clean's and ball_snow's side rims -41 -> -48 %, -51 -> -57 %; from -0.3 down
// ball_grey's rims keep +49 % (docs/benchmarks.md, grey-rims-53).
constexpr double kShadowedCarrierCosine = -0.25;

// The share of a beam's extinction that its forward peak keeps on the beam's way, omega g^2 (the delta scaling,
// grey: the middle channel), which forwardPeakThrough and beamsInRamp take off the uncollided extinction.
double forwardKeptShare(const VolumeOptics &optics) { return optics.albedo.y * optics.g * optics.g; }

// The returned grazing sun carried through the density ramp: voxel c (outside the unknowns, carrying its surface's
// radiance) in front of smooth surface voxels within two voxels whose peaked lobe (the sun returned sharply
// forwards, Method 5) travels towards it takes their peaked lobes where these are over twice its own (elsewhere
// its surface holds as much: a march towards the suns saved), weighted by the cosine squared between a lobe's
// axis and the way to c and by how much its surface faces c, in the share that reaches c (below: the suns' or
// the peaks' own delta-scaled transmittance, the larger). On a lit rim seen against the sun the camera ray crosses the ramp at the
// top and becomes opaque in its camera side, whose own surface voxels take the sun at grazing incidence and
// hold little peak (mu0 0-0.2), while the light there is the lit top's forward return travelling through
// (ball_issue's top row: the reference's source 0.3-0.4 in the ramp's first optical depth, the bake's 0.15-0.2;
// ball_grey's top row seen against the sun -55 -> -37 %). Not across sharp edges (a peak whose way to c passes
// an edge voxel: their faces' light leaves face by face; slab_thick 4.4 -> 4.7 % with them, and left out
// wherever an edge voxel lay beside c, ball_issue's side rims seen against the sun stayed at -59 %), nor from
// traced voxels (their peak is their own beams' scattering). bench/bake_suite.py: docs/bake.md, Accuracy.
//
// peaks: the surface voxels holding a peaked lobe, read from the at most eight leaves around c (BlockMask): an
// index lookup for each of the 124 voxels around c took most of this walk's time. normal: the carrying surfaces'
// (facingAverage), against which kShadowedCarrierCosine is taken; sunAt: the quarter-voxel lattice's suns. rampPart
// (facingAverage's) takes the peaks' parts alike.
void forwardPeakThrough(const Scene &scene, const SnowTopology &topo, const openvdb::Coord &c,
                        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index,
                        TracedIndex &tracedIndex, const SourceValues &source,
                        openvdb::tree::ValueAccessor<const openvdb::BoolTree> &peaks, Medium::ColumnMarcher &marcher,
                        QuarterPointSun &sunAt, const glm::dvec3 &normal, Source &S, Source &rampPart) {
    struct Offset {
        openvdb::Coord from;  // c minus the way to c
        glm::dvec3 towards;   // unit
        bool beside;          // within one voxel
        openvdb::Coord lo, hi;  // the voxels around the midpoint of the way, from `from`
    };
    static const std::vector<Offset> offsets = [] {
        const auto half = [](int v, bool up) { return int(up ? std::ceil(v / 2.0) : std::floor(v / 2.0)); };
        std::vector<Offset> out;
        for (int dx = -2; dx <= 2; ++dx)
            for (int dy = -2; dy <= 2; ++dy)
                for (int dz = -2; dz <= 2; ++dz)
                    if (dx || dy || dz)
                        out.push_back({openvdb::Coord(-dx, -dy, -dz), glm::normalize(glm::dvec3(dx, dy, dz)),
                                       std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) == 1,
                                       openvdb::Coord(half(dx, false), half(dy, false), half(dz, false)),
                                       openvdb::Coord(half(dx, true), half(dy, true), half(dz, true))});
        return out;
    }();
    const auto sharpAt = [&](const openvdb::Coord &v) {
        const std::int32_t k = index.getValue(v);
        return k >= 0 && topo.patches[k].sharp;
    };
    const BlockMask peakAt(peaks, c, 2);
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    // delta-Eddington: the share f = omega g^2 of the scattered light stays in the forward beam (extinction
    // sigma_t (1 - f)).
    const double forwardKept = forwardKeptShare(optics);
    const glm::dvec3 centre = medium.voxelCentre(c);
    glm::dvec3 p0(0.0), p1(0.0);
    double total = 0.0;
    struct Taken {
        openvdb::Coord from;
        std::int32_t j;  // its unknown
        double w;
    };
    std::array<Taken, 124> taken;  // the peaks taken (of the 124 offsets) and their weights
    std::size_t takenCount = 0;
    for (const Offset &o : offsets) {
        const openvdb::Coord from = c + o.from;
        if (!peakAt.isOn(from)) continue;
        const std::int32_t j = index.getValue(from);
        if (!o.beside && (sharpAt(from + o.lo) || sharpAt(from + o.hi))) continue;  // its light passes an edge
        const double facing = glm::dot(topo.patches[j].normal, o.towards);
        if (facing <= 0.0 || tracedIndex.getValue(from) >= 0) continue;
        const Source v = source[j];
        const double along = glm::dot(glm::normalize(glm::dvec3(v.peak1)), o.towards);
        if (along <= 0.0) continue;
        const double w = along * along * facing;
        p0 += w * glm::dvec3(v.peak0), p1 += w * glm::dvec3(v.peak1), total += w;
        taken[takenCount++] = {from, j, w};
    }
    if (!(total > 0.0) || (p0.x + p0.y + p0.z) / total <= 2.0 * double(S.peak0.x + S.peak0.y + S.peak0.z)) return;
    // The peaks' ramp parts only where they are carried: most ramp voxels near a peak end above.
    glm::dvec3 ramp0(0.0), ramp1(0.0);
    double crossing = 0.0;
    for (std::size_t k = 0; k < takenCount; ++k) {
        const Source r = source.rampPeaks.with(BroadLobe{}, std::size_t(taken[k].j));
        ramp0 += taken[k].w * glm::dvec3(r.peak0), ramp1 += taken[k].w * glm::dvec3(r.peak1);
        crossing += taken[k].w * rampCrossing(medium, medium.voxelCentre(taken[k].from), centre, forwardKept, marcher);
    }
    double arriving = 0.0, outside = 0.0;  // W/m^2 (green): delta-scaled through the snow, and outside it
    for (std::size_t b = 0; b < scene.suns.size(); ++b) {
        const SunLight &sun = scene.suns[b];
        outside += sun.irradiance.y;
        if (glm::dot(normal, sun.direction) < kShadowedCarrierCosine) {
            if (!occludersHide(scene, centre, sun.direction))
                arriving +=
                    sun.irradiance.y * hatSunTransmittance(c, b, sun.direction, 1.0 - forwardKept, marcher, sunAt);
        } else if (sun.irradiance.y > 0.0f) {
            const double centreLit = beamAt(scene, b, centre, 1, 0, 0, marcher, nullptr, Crossing::Uncollided)
                                         .irradiance.y / sun.irradiance.y;
            arriving += sun.irradiance.y * std::pow(centreLit, 1.0 - forwardKept);
        }
    }
    // The lit top's forward return crosses the ramp on a rim's camera side though the sun reaches it only through
    // the top's own snow: the share carried is the delta-scaled sun's transmittance to c (ball_issue's view against
    // the sun -27 -> -20 %; with f = g -17 %, but ball_clean's, 5 mm voxels of optical depth 30, -0 -> +4 %: branch
    // seen-sun) or, where more, the delta-scaled transmittance of the peaks' own way through the ramp from the
    // boundary of their voxels on to c (rampCrossing: -20 -> -17 %, its top row's middle blocks -26 -> -17 %;
    // that way alone, ball_grey's top row -31 -> -43 %, its sun crossing less snow than the way: branch lit-top).
    // Beside carriers well past the terminator (kShadowedCarrierCosine) the sun's share is averaged over c's hat.
    const double sunLit = outside > 0.0 ? arriving / outside : 0.0;
    const double lit = std::max(sunLit, crossing / total);
    S.peak0 = glm::vec3(lit * p0 / total + (1.0 - lit) * glm::dvec3(S.peak0));
    S.peak1 = glm::vec3(lit * p1 / total + (1.0 - lit) * glm::dvec3(S.peak1));
    rampPart.peak0 = glm::vec3(lit * ramp0 / total + (1.0 - lit) * glm::dvec3(rampPart.peak0));
    rampPart.peak1 = glm::vec3(lit * ramp1 / total + (1.0 - lit) * glm::dvec3(rampPart.peak1));
}

// The skin beneath a ramp voxel's carrier (the surface voxel facing it most): its curvature (per voxel,
// surfaceCurvature), ramp thickness (voxels: 2 m / rho as its patch's, patchRampMass over densityBeneath, read from the
// density, the topology keeping no links here) and the density beneath it. LimbSkins finds each once per carrier: the
// ramp voxels around a carrier share it, and each walked the carrier's column and read its curvature again (the
// curvature twice more: the ramp's gate, RampOfThickConvexSnow, asked it per ramp voxel).
struct LimbSkin {
    double curvature = 0.0, thickness = 0.0, beneath = 0.0;  // per voxel, voxels, kg/m^3; thickness 0: none
};

class LimbSkins {
  public:
    // carrier: any voxel (surfaceCurvature reads 0 off the surface).
    double curvature(const SnowTopology &topo, const openvdb::Coord &carrier,
                     openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index) {
        return carried(topo, carrier, index).skin.curvature;
    }
    // carrier: a smooth surface voxel, j its unknown.
    const LimbSkin &at(const SnowTopology &topo, const openvdb::Coord &carrier, std::int32_t j,
                       openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, Medium::Accessor &density,
                       Medium::ColumnMarcher &marcher, const Medium &medium) {
        Carried &found = carried(topo, carrier, index);
        LimbSkin &skin = found.skin;
        if (found.skinFound) return skin;
        found.skinFound = true;
        if (!(skin.curvature > 0.0)) return skin;
        const glm::dvec3 n = topo.patches[std::size_t(j)].normal;
        const float under = density.getValue(carrier + faceStep(faceBeneath(n)));
        skin.beneath = under > 0.0f ? under : density.getValue(carrier);
        if (!(skin.beneath > 0.0)) return skin;
        const double h = medium.voxelSize();
        const double mass =  // kg/m^2
            marcher.column(medium.voxelCentre(carrier), n, 4.0 * h, std::numeric_limits<double>::infinity());
        skin.thickness = 2.0 * mass / (skin.beneath * h);
        return skin;
    }
    // carrier: a surface voxel, j its unknown; voxels from its node out to its surface (skin_ring.h, surfaceOffset).
    double surfaceOffset(const SnowTopology &topo, const openvdb::Coord &carrier, std::int32_t j,
                         openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, Medium::Accessor &density,
                         const Medium &medium) {
        Carried &found = carried(topo, carrier, index);
        if (!found.offset)
            found.offset = bake::surfaceOffset(medium, carrier, topo.patches[std::size_t(j)].normal, density);
        return *found.offset;
    }
    // The carriers of a leaf's voxels lie within a voxel of it: cleared per leaf, the map stays small.
    void clear() { skins_.clear(); }

  private:
    struct Carried {
        LimbSkin skin;  // its curvature found on entry, the rest once `at` asks
        bool skinFound = false;
        std::optional<double> offset;  // surfaceOffset, once asked
    };
    Carried &carried(const SnowTopology &topo, const openvdb::Coord &carrier,
                     openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index) {
        const auto [it, inserted] = skins_.try_emplace(carrier);
        if (inserted) it->second.skin.curvature = surfaceCurvature(topo, carrier, index);
        return it->second;
    }
    std::map<openvdb::Coord, Carried> skins_;
};

// Whether the surface carrying a ramp voxel (`carrier`, the surface voxel facing it most: facingAverage) curves away
// faster than a sphere of kSkyRampRadius voxels (skin_ring.h): only there is the sky the ramp sees below its plane
// past the snow's limb worth its marches. Of the car's 710 k ramp voxels 39 k pass beside thick snow (73 k at 8
// voxels).
bool onConvexSurface(const SnowTopology &topo, const openvdb::Coord &carrier,
                     openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, LimbSkins &skins) {
    return smallBall(skins.curvature(topo, carrier, index));
}

// The suns' light a convex surface carries out into its ramp, shown over the larger sphere a ramp voxel d voxels out
// lies on: radiance per m^2 of the sphere of radius R shown over one of R + d divides by (1 + kappa d)^2 (the balls'
// lit cap rendered at 1.19 times the truth while the patches let out the truth's; docs/benchmarks.md, cap-shape,
// cap-spread). The whole divergence: the sun the skin intercepts beyond R, which the undivided light stood for, is
// its own source now (skinRingGrowth, given to the patches in assemble); a small ball's, which takes no ring,
// divides by (1 + kappa d)^kSmallBallSpread (carriedSunSpread). The sky's carried light is not spread: an
// even sky on the sphere of R + d brings that much more, the skin's own ring (ball_sky is right as it is), so the
// beams' part alone (SourceValues::skyShare, the solves' split; the peaked lobe is the beams' whole). d from the
// carrier's own surface (surfaceOffset: the density's half level, where the patches' sphere lies; from the node or
// the staircase's half voxel instead the balls' bias swung by 5 points: docs/benchmarks.md, cap-ring).
void spreadCarriedSun(const Medium &medium, const SnowTopology &topo, const SourceValues &source,
                      const openvdb::Coord &c, const openvdb::Coord &carrier, const glm::dvec3 &facing,
                      openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, Medium::Accessor &density,
                      LimbSkins &skins, Source &S, Source &rampPart) {
    if (source.skyShare.values().empty() || glm::length(facing) == 0.0) return;
    const double kappa = skins.curvature(topo, carrier, index);
    if (!spreadsAsSphere(topo, carrier, index, kappa)) return;
    const glm::dvec3 out(c.x() - carrier.x(), c.y() - carrier.y(), c.z() - carrier.z());
    const std::int32_t j = index.getValue(carrier);
    const double d = glm::dot(out, facing) - skins.surfaceOffset(topo, carrier, j, index, density, medium);  // voxels
    if (d <= 0.0) return;
    const float spread = float(carriedSunSpread(kappa, d));
    const float sky = source.skyShare[std::size_t(index.getValue(carrier))], keep = sky + (1.0f - sky) * spread;
    S.l0 *= keep, S.l1 *= keep;
    S.peak0 *= spread, S.peak1 *= spread, rampPart.peak0 *= spread, rampPart.peak1 *= spread;
}

// Whether ramp voxel c lies beside optically thick snow: some voxel of its 3^3 block at least a fringe's density
// (kFringeOpticalDepth, buildSnowTopology's float threshold). Thinner, the light crossing it is the surface's own.
bool besideThickSnow(const Medium &medium, Medium::Accessor &density, const openvdb::Coord &c) {
    const float fringeDensity =
        float(kFringeOpticalDepth / (medium.optics().extinctionPerDensity * medium.voxelSize()));  // kg/m^3
    for (int k = 0; k < 27; ++k)
        if (density.getValue(c + blockOffset(k)) >= fringeDensity) return true;
    return false;
}

// Whether ramp voxel c is the ramp of optically thick convex snow (besideThickSnow, its carrier onConvexSurface),
// the test beamsInRamp and skyInRamp share: asked only past their cheap early exits, found at most once per voxel.
// Asked past a zero normal's exit: there no surface faces c and carrier is none (surfaceCurvature reads 0).
class RampOfThickConvexSnow {
  public:
    RampOfThickConvexSnow(const SnowTopology &topo, const openvdb::Coord &c, const openvdb::Coord &carrier,
                          openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, LimbSkins &skins,
                          Medium::Accessor &density, const Medium &medium)
        : topo_(topo), c_(c), carrier_(carrier), index_(index), skins_(skins), density_(density), medium_(medium) {}
    bool operator()() {
        if (!asked_) {
            thickConvex_ = besideThickSnow(medium_, density_, c_) && onConvexSurface(topo_, carrier_, index_, skins_);
            asked_ = true;
        }
        return thickConvex_;
    }

  private:
    const SnowTopology &topo_;
    const openvdb::Coord &c_, &carrier_;
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index_;
    LimbSkins &skins_;
    Medium::Accessor &density_;
    const Medium &medium_;
    bool asked_ = false, thickConvex_ = false;  // two flags, not std::optional<bool>: GCC 12 warns it unset
};

// How beam b, meeting the carrying surfaces at mu0, crosses the snow on its way to a ramp voxel it scatters in
// (beamsInRamp). A sun or an area lamp's piece the surfaces take at grazing incidence (0 <= mu0) crosses the ramp's
// outer part on a long chord before c: there the light scattered into the phase function's forward peak keeps the
// beam's way and scatters again in c, the delta-scaled beam (Crossing::Forward). Uncollided, the 5 cm ball of omega
// 0.9 and g 0.85 at 20 optical depths per voxel let out 0.88 of the Monte Carlo's power, 0.71-0.74 of it 120-180
// degrees from the sun (0.90, and 0.75-0.82, so; docs/benchmarks.md, lead-92). Past the terminator the chord skims
// the limb, off which the forward-scattered light spreads: delta-scaled there too, ball_issue's side limbs seen
// against the sun read +36 and +29 % (+24 and +16 % uncollided). A point or spot lamp's ways fan out from one point:
// delta-scaled, ball_grey's blocks past its terminator seen against it read +41 % (+37 % uncollided: lamp-shell).
Crossing rampBeamCrossing(const Scene &scene, std::size_t b, double mu0) {
    const bool lineUp = b < scene.suns.size() || scene.lamps[b - scene.suns.size()].isArea();
    return lineUp && mu0 >= 0.0 ? Crossing::Forward : Crossing::Uncollided;
}

// The beams' light (suns, lamps, area lamps' pieces: beamLightsRamp) scattered once in ramp voxel c (outside the
// unknowns, carrying its surface's radiance) in front of surfaces that take them at grazing incidence or not at all
// (kGrazingSunCosine): the peaked lobe of k = g about each beam's travel, of mean omega E T / 4 pi, T the snow's
// transmittance (rampBeamCrossing) averaged over c's trilinear hat weighted by the density (what the renderer's
// emission weighs; 4^3 points), the occluders' shadow taken at c's centre, where it holds more than c's own peak and
// no sun the surfaces take (mu0 >= kGrazingSunCosine) lights c. Where the surfaces take a lamp or an area lamp's piece,
// c's carried peak holds that beam's return too, which the others' ramp light does not stand for: only the others'
// return (rampPart: the carriers' SurfaceLight::rampPeak0, weighted as the carried peak) is set against their ramp
// light, the taken beams' kept. Replacing the whole peak lost the taken pieces' return (area-pieces); adding the
// ramp light to it counted the others' return twice (the 84 % of the carried peak under a low 60 cm square lamp
// over a flat slab; a sun at 20 degrees so read +14.7 % where compared -0.8 %; seen from above the lamp +4.5 -> +1.0
// %, its side views -5.8 to -6.9 % -> -8.3 to -10.1 %, those of its pieces below mu0 0.2, as the sun at 10 degrees,
// -28 %; docs/benchmarks.md, peak-split). A convex
// surface's ramp reaches into the sun past its terminator, where the surfaces' half-space model has no sun (mu0 <= 0)
// or little (a lit patch returns E mu0 per area, the ramp beside it scatters E T): ball_grey's rims seen against the
// sun (bench/bake_suite.py; docs/bake.md, Method 7). The average, not T at c's centre: an air voxel just outside a limb
// has T = 1 at its centre and shadowed snow in its hat (T at the centre read ball_grey's equator rims seen against the
// sun +200 to +270 %); 3^3 points (the hat's trapezoid rule) lost slab_thick's and box_sharp's gains.
// In the ramp of thick snow curving away faster than kSkyRampRadius (RampOfThickConvexSnow) it is added to the carried
// peak: the carried peaks are the surface's half-space return, while there the sun crosses the ramp's outer part on a
// long chord and scatters in it before reaching the snow (ball_issue's top rim seen against the sun: 75 % of its light
// entered outside r + 0.3 voxels, orders 2-8 most; docs/benchmarks.md, rim-forward). Added on thin snow or flat walls
// it lost: ball_thin, spray_lumps, slab_thin_forward, slab_thick. Added whole also where the carriers take the sun a
// little (0 < mu0 < kGrazingSunCosine), whose ramp mass the half-space model holds too (patchRampMass), with a step
// at kGrazingSunCosine: tapered by 1 - mu0 / kGrazingSunCosine (continuous), or added only where mu0 <= 0, it lost
// (ball_issue's worst block +36 -> -40, -48 %, ball_grey 8.0 -> 8.3, 8.4 %; docs/benchmarks.md, mends-rim52).
// A lamp's light is marched from each of the hat's points (its way varies across the voxel), over lampSamples points of
// the lamp (seed, stream: beamAt's), the occluders' shadow taken at c's centre; its 1 / r^2 in the irradiance.
// normal: the carrying surfaces' (facingAverage), zero where none faces c; rampPart: facingAverage's.
void beamsInRamp(const Scene &scene, const openvdb::Coord &c, const glm::dvec3 &normal, Medium::ColumnMarcher &marcher,
                 QuarterPointSun &sunAt, RampOfThickConvexSnow &rampOfThickConvexSnow, int lampSamples,
                 std::uint64_t seed, std::uint64_t stream, const Source &rampPart, Source &S) {
    if (glm::length(normal) == 0.0) return;
    const glm::dvec3 centre = scene.medium->voxelCentre(c);
    const auto litInRamp = [&](std::size_t b) {
        return beamLightsRamp(scene, b, glm::dot(normal, towardsBeam(scene, b, centre)));
    };
    // The occluders' shadow rays below only matter where some beam meets the surfaces grazingly or not at all: where
    // none does, each either returns or adds nothing (and peaks are never negative). The car's ramp, mostly lit.
    std::size_t beams = 0;
    while (beams < beamCount(scene) && !litInRamp(beams)) ++beams;
    if (beams == beamCount(scene)) return;
    const VolumeOptics &optics = scene.medium->optics();
    const double forwardPower = 1.0 - forwardKeptShare(optics);  // Crossing::Forward from the uncollided T
    Source single;
    bool lampTaken = false;  // a lamp or piece the surfaces take: its return is in c's carried peak
    for (std::size_t b = 0; b < beamCount(scene); ++b) {
        const bool sun = b < scene.suns.size();
        if (sun && occludersHide(scene, centre, scene.suns[b].direction)) continue;
        // A sun the surface takes has its forward peak in c's one carried peak: kept whole (replacing it dropped that
        // peak and its direction; test_ramp_single_scattering_keeps_a_second_suns_forward_peak). A lamp's pieces are
        // tested each on its own: one the surface takes hid the others' ramp light (lamp-ramp), and its return stays in
        // the carried peak beside the others' (area-pieces, peak-split; docs/benchmarks.md).
        if (!litInRamp(b)) {
            if (sun) return;
            lampTaken = true;
            continue;
        }
        const Crossing crossing = rampBeamCrossing(scene, b, glm::dot(normal, towardsBeam(scene, b, centre)));
        const glm::dvec3 lit =  // W/m^2: the beam's mean over c's hat
            sun ? hatSunTransmittance(c, b, scene.suns[b].direction,
                                      crossing == Crossing::Forward ? forwardPower : 1.0, marcher, sunAt) *
                      glm::dvec3(scene.suns[b].irradiance)
                : hatAverage<glm::dvec3>(c, marcher, [&](const openvdb::Coord &q) {
                      const glm::dvec3 point = scene.medium->indexToWorld(glm::dvec3(q.x(), q.y(), q.z()) / 4.0);
                      return glm::dvec3(beamAt(scene, b, point, lampSamples, seed, stream, marcher, &centre,
                                               crossing).irradiance);
                  });
        single.addPeak(lit * glm::dvec3(optics.albedo) * kInvFourPi, crossingAnisotropy(optics.g),
                       -towardsBeam(scene, b, centre));
    }
    const auto sum = [](const glm::vec3 &v) { return v.x + v.y + v.z; };
    if (rampOfThickConvexSnow()) {
        S.add(single);
    } else if (lampTaken) {
        // The taken beams' return stays; the others' return (rampPart) is set against their ramp light alone.
        const Source &others = sum(single.peak0) > sum(rampPart.peak0) ? single : rampPart;
        S.peak0 = glm::max(S.peak0 - rampPart.peak0, glm::vec3(0.0f)) + others.peak0;
        S.peak1 = S.peak1 - rampPart.peak1 + others.peak1;
    } else if (sum(single.peak0) > sum(S.peak0)) {
        S.peak0 = single.peak0, S.peak1 = single.peak1;
    }
}

// The sky's light from below ramp voxel c's plane (directions d . normal < 0) scattered once in it: omega / 4 pi
// times the integral of L_sky(d) T(d), T the snow's uncollided transmittance averaged over c's trilinear hat
// weighted by the density (as beamsInRamp's), a way crossing an unknown's voxel blocked (the diffusion holds what
// enters the unknowns), added to c's broad lobe as isotropic. The carried surface radiance holds the half-space's
// sky, which reaches the surface from above its plane only; a convex surface's ramp also sees sky from below it
// through the thin snow past the limb (zero on flat snow: the snow below blocks it; ball_issue under the sky alone
// -6.8 -> -5.7 %, bench/ball_sky_split.py). kSkyBands x kSkyAzimuths directions of equal solid angle below the
// plane (4 x 8 gave the suite's figures within 0.1 points at 1.8 times the marches), the occluders' shadow taken
// at c's centre.
constexpr int kSkyBands = 3, kSkyAzimuths = 6;

void skyInRamp(const Scene &scene, const openvdb::Coord &c, const glm::dvec3 &normal,
               openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index,
               RampOfThickConvexSnow &rampOfThickConvexSnow, Medium::ColumnMarcher &marcher, Source &S) {
    // Only the ramp of optically thick convex snow (ball_thin, slab_thin, spray_lumps read +0.3, +0.3 and +1.1 points
    // of bias with thinner).
    if (glm::length(normal) == 0.0 || scene.sky.isBlack() || !rampOfThickConvexSnow()) return;
    const Medium &medium = *scene.medium;
    const double perColumn = medium.optics().extinctionPerDensity;  // m^2/kg: uncollided
    // c's trilinear hat by the midpoint rule on 2^3 points (half voxels from c's centre; 4^3 cost 8 times more for
    // the suite's figures within 0.1 points).
    std::array<std::pair<glm::dvec3, double>, 8> hat;  // the points (m) and weights holding snow
    int points = 0;
    double weights = 0.0;
    for (int k = 0; k < 8; ++k) {
        const openvdb::Vec3d q(c.x() + (k & 1 ? 0.5 : -0.5), c.y() + (k & 2 ? 0.5 : -0.5),
                               c.z() + (k & 4 ? 0.5 : -0.5));
        const double w = marcher.densityAt(q);
        if (w <= 0.0) continue;
        hat[points++] = {medium.indexToWorld(glm::dvec3(q.x(), q.y(), q.z())), w};
        weights += w;
    }
    if (points == 0) return;
    const double limit = std::log(1e5) / perColumn;  // kg/m^2: the transmittance below 1e-5
    // The column from `from` along d, up to the limit where the way crosses an unknown's voxel.
    auto columnTo = [&](const glm::dvec3 &from, const glm::dvec3 &d) {
        double column = 0.0;  // kg/m^2
        marcher.march(from, d, std::numeric_limits<double>::infinity(), 0.5,
                      [&](const openvdb::Vec3d &p, double length) {
                          column = index.getValue(openvdb::Coord::round(p)) >= 0
                                       ? limit
                                       : column + marcher.densityAt(p) * length;
                          return column < limit;
                      });
        return column;
    };
    auto direction = [&](int band, int azimuth) {
        return directionAround(normal, -(band + 0.5) / kSkyBands, 2.0 * kPi * (azimuth + 0.5) / kSkyAzimuths);
    };
    // Even over convex snow the sky below the plane can be blocked (the snow's far side): where the band nearest the
    // plane, marched from c's centre, finds none, the rest is not marched.
    const glm::dvec3 centre = medium.voxelCentre(c);
    bool seen = false;
    for (int j = 0; j < kSkyAzimuths && !seen; ++j) seen = columnTo(centre, direction(0, j)) < limit;
    if (!seen) return;
    constexpr double kSolidAngle = 2.0 * kPi / (kSkyBands * kSkyAzimuths);  // sr per direction
    glm::dvec3 arriving(0.0);  // W/m^2 per channel
    for (int i = 0; i < kSkyBands; ++i)
        for (int j = 0; j < kSkyAzimuths; ++j) {
            const glm::dvec3 d = direction(i, j);
            // The occluders' one shadow ray before the hat's marches: a direction an occluder hides needs none.
            if (occludersHide(scene, centre, d)) continue;
            double transmitted = 0.0;
            for (int k = 0; k < points; ++k)
                if (const double column = columnTo(hat[k].first, d); column < limit)
                    transmitted += hat[k].second * std::exp(-perColumn * column);
            if (transmitted <= 0.0) continue;
            arriving += transmitted / weights * kSolidAngle * scene.sky.radianceFrom(d);
        }
    S.l0 += glm::vec3(arriving * glm::dvec3(medium.optics().albedo) * kInvFourPi);
}

// The sun's light the skin of a convex surface carries past its limb (limb_carry.h), scattered once in ramp voxel c
// (outside the unknowns, carrying its surface's radiance) beside optically thick snow (besideThickSnow) on its way:
// a peaked lobe of k = g about the sun's travel, of mean omega F / 4 pi, the carried flux F = omega g^2 A E
// limbCarriedFlux averaged over c's trilinear hat weighted by the density (what the renderer's emission weighs; 4^3
// points), E the sun's irradiance, A the half-space's albedo of it at the carrier's sun cosine (0.05 at least), f the
// density over the carrier's beneath it; past the terminator times the delta-scaled sun's transmittance there (the
// lines' way through the skin from the terminator on; without it ball_grey's worst block read +67 %), omega g^2 and
// the exponent 1 - omega g^2 each channel's.
// Placed by height: the outer skin, whose camera chords cross only the ramp, carries what the mass above it
// scattered. Added to the patches' return, not taken from it: taken (omega g^2 (1 - z*/Delta)^2 of each smooth patch's
// returned sun) it darkened the view against the sun, whose light the carried peaks are (ball_issue -13.5 -> -18 to
// -28 %; docs/benchmarks.md, limb-ramp); placed by the sun's chord (E (T_delta - T)) and taken from the patches'
// peaks as much as leaves on their lines, -12.6 -> -24 % (limb-conserve). The occluders' shadow taken at c's centre.
// normal: the carrying surfaces' (facingAverage), zero where none faces c; carrier: the surface voxel facing c most;
// sunAt: the quarter-voxel lattice's suns; skins: the carriers' skins (LimbSkins).
void limbCarriedInRamp(const Scene &scene, const SnowTopology &topo, const openvdb::Coord &c,
                       const openvdb::Coord &carrier, const glm::dvec3 &normal,
                       openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, Medium::Accessor &density,
                       Medium::ColumnMarcher &marcher, QuarterPointSun &sunAt, LimbSkins &skins, Source &S) {
    if (glm::length(normal) == 0.0 || scene.suns.empty()) return;
    const std::int32_t j = index.getValue(carrier);
    if (j < 0 || !topo.patches[j].isSurface() || topo.patches[j].sharp) return;
    const Medium &medium = *scene.medium;
    const LimbSkin &skin = skins.at(topo, carrier, j, index, density, marcher, medium);
    if (!(skin.thickness > 0.0) || !besideThickSnow(medium, density, c)) return;
    const VolumeOptics &optics = medium.optics();
    glm::dvec3 kept;  // per channel: omega g^2, and 1 - it the delta-scaled transmittance's exponent
    for (int ch = 0; ch < 3; ++ch) kept[ch] = limbForwardFraction(optics.albedo[ch], optics.g);
    const glm::dvec3 centre = medium.voxelCentre(c);
    for (std::size_t b = 0; b < scene.suns.size(); ++b) {
        const SunLight &sun = scene.suns[b];
        const double mu = glm::dot(normal, sun.direction);
        if (mu * mu >= 2.0 * skin.curvature * skin.thickness || occludersHide(scene, centre, sun.direction)) continue;
        const glm::dvec3 flux = hatAverage<glm::dvec3>(c, marcher, [&](const openvdb::Coord &q) {
            const double f = marcher.densityAt(openvdb::Vec3d(q.x(), q.y(), q.z()) / 4.0) / skin.beneath;
            const double carried = limbCarriedFlux(f, mu, skin.curvature, skin.thickness);
            if (!(carried > 0.0) || mu >= 0.0) return glm::dvec3(carried);
            const double T = sunAt.at(b, sun.direction, q);
            return carried *
                   glm::dvec3(std::pow(T, 1.0 - kept.x), std::pow(T, 1.0 - kept.y), std::pow(T, 1.0 - kept.z));
        });
        if (!(flux.x + flux.y + flux.z > 0.0)) continue;
        glm::dvec3 mean(0.0);
        for (int ch = 0; ch < 3; ++ch) {
            const double omega = optics.albedo[ch];
            const double A = sunLobe(optics.g, std::max(mu, 0.05), absorptionParameter(omega, optics.g)).albedo;
            mean[ch] = kept[ch] * A * flux[ch] * sun.irradiance[ch] * omega * kInvFourPi;
        }
        S.addPeak(mean, crossingAnisotropy(optics.g), -sun.direction);
    }
}

}  // namespace

// gathering: the values the gathering reads alone (those beside snow, besideSnow: the grids carry the surface's
// radiance two voxels out, the gathering needs one), without the ramp's own light: the returned grazing sun carried
// through it (forwardPeakThrough; it cost the car 0.8 processor seconds there), the suns and the sky from below its
// plane scattered once in it (beamsInRamp: no peaks are marked when gathering; skyInRamp). What cameras see of a lit
// rim; the sky rays between snow surfaces hardly meet it.
GridValues gridValues(const Scene &scene, const SnowTopology &topo, const SourceValues &source,
                      const MonteCarloVoxels &traced, const Preset &preset, const BakeSettings &settings,
                      bool gathering, const SubProgress &progress) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    GridValues out;
    out.topology = std::make_shared<openvdb::BoolTree>(medium.density().tree(), false, openvdb::TopologyCopy());
    openvdb::tools::dilateActiveValues(*out.topology, 3, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    openvdb::tree::LeafManager<const openvdb::BoolTree> leaves(*out.topology);
    using Blocks = std::vector<VoxelValueBlock>;

    // Average of the 26 neighbours accepted by `take`, read by `value`; false if none.
    auto average = [](const openvdb::Coord &c, const auto &take, const auto &value, Source &S) {
        int count = 0;
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const openvdb::Coord n = c.offsetBy(dx, dy, dz);
                    if (!take(n)) continue;
                    const Source v = value(n);
                    S.add(v), ++count;
                }
        if (count) S.divideBy(float(count));
        return count > 0;
    };
    // Where forwardPeakThrough may find a peak: within two voxels of a smooth surface voxel holding one (the car's
    // grids took 4.6 processor seconds searching around every voxel next to a surface voxel, 4.3-4.4 so, 3.3 without).
    // peaks: smooth surface voxels holding a peaked lobe. A sharp edge's peak (its faces' grazing sun) stays its
    // own: carried through the ramp too, ball_issue's view against the sun read -29 % (-27 % without).
    openvdb::BoolTree nearPeak(false), peaks(false);
    if (!gathering) {
        std::vector<bool> peaked(source.broad.size(), false);  // by unknown
        for (const PeakedLobes::Peak &peak : source.peaked.peaks())
            peaked[peak.key] = glm::length(peak.peak1) > 0.0f;
        for (auto it = topo.index->cbeginValueOn(); it; ++it)
            if (const std::int32_t j = *it;
                j >= 0 && peaked[j] && topo.patches[j].isSurface() && !topo.patches[j].sharp)
                peaks.setValueOn(it.getCoord());
        nearPeak.topologyUnion(peaks);
        openvdb::tools::dilateActiveValues(nearPeak, 2, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                           openvdb::tools::IGNORE_TILES);
    }
    // Where facingAverage can find a surface voxel (within one voxel of one) and, beyond that, where a voxel can
    // have a carried neighbour or carry a traced voxel's face (within one of those or of a traced voxel): elsewhere
    // none looks at its neighbours (the car's 3 M voxels of margin and fringe took 78 M lookups for 0.8 M values).
    openvdb::BoolTree nearSurface(*topo.index, false, openvdb::TopologyCopy());
    openvdb::tree::LeafManager<openvdb::BoolTree>(nearSurface).foreach(
        [&](openvdb::BoolTree::LeafNodeType &leaf, std::size_t) {
            const auto &indexLeaf = *topo.index->probeConstLeaf(leaf.origin());
            for (auto it = leaf.beginValueOn(); it; ++it)
                if (!topo.patches[std::size_t(indexLeaf.getValue(it.pos()))].isSurface()) it.setValueOff();
        });
    openvdb::tools::dilateActiveValues(nearSurface, 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    openvdb::BoolTree nearCarried(nearSurface);
    nearCarried.topologyUnion(*traced.index);
    openvdb::tools::dilateActiveValues(nearCarried, 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    // First: traced voxels, the air across a traced voxel's face (faceCarried: a lump's fringe's outer face too, two
    // voxels from the surface unknowns: spray_dense over 16 seeds 16.27 -> 16.20 % per block, 15 lower; docs/
    // benchmarks.md, lump-contrast), and the voxels next to surface voxels (unknowns hold their own source).
    Blocks perLeaf(leaves.leafCount());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        TracedIndex tracedIndex(traced);
        openvdb::tree::ValueAccessor<const openvdb::BoolTree> nearPeakAt(nearPeak), peaksAt(peaks),
            nearSurfaceAt(nearSurface), nearCarriedAt(nearCarried);
        Medium::ColumnMarcher marcher(medium);
        Medium::Accessor density = medium.accessor();
        QuarterPointSun sunAt(medium, scene.suns.size());
        LimbSkins limbSkins;
        WorkCheck work(progress);
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            sunAt.startLeaf(leaves.leaf(l).origin());
            limbSkins.clear();
            for (auto it = leaves.leaf(l).cbeginValueOn(); it; ++it) {
                work.add(WorkCheck::kVoxel);
                const openvdb::Coord c = it.getCoord();
                const std::int32_t t = tracedIndex.getValue(c);
                Source S, rampPart;
                glm::dvec3 facing(0.0);  // the carrying surfaces' normal
                openvdb::Coord carrier;  // and the surface voxel facing c most
                RampOfThickConvexSnow rampOfThickConvexSnow(topo, c, carrier, index, limbSkins, density, medium);
                // A traced carrier's value is the Monte Carlo's over its hat, the ramp's sky and limb light in it,
                // which skyInRamp and limbCarriedInRamp add to the half-space surface's (spray_dense over seeds 0-7
                // 13.31 -> 13.25 % per block; docs/benchmarks.md, spray-rims 2026-12-04).
                bool tracedCarrier = false;
                if (t >= 0) S = ownValue(traced, t);
                else if (!nearCarriedAt.isValueOn(c) || index.getValue(c) >= 0) continue;
                else if (faceCarried(c, tracedIndex, traced, S)) {}
                else if (!nearSurfaceAt.isValueOn(c)) continue;
                else if (!facingAverage(topo, c, index, source, tracedIndex, traced, S, rampPart, facing, carrier))
                    continue;
                else {
                    tracedCarrier = tracedIndex.getValue(carrier) >= 0;
                    spreadCarriedSun(medium, topo, source, c, carrier, facing, index, density, limbSkins, S, rampPart);
                    if (nearPeakAt.isValueOn(c)) {
                        forwardPeakThrough(scene, topo, c, index, tracedIndex, source, peaksAt, marcher, sunAt, facing,
                                           S, rampPart);
                        beamsInRamp(scene, c, facing, marcher, sunAt, rampOfThickConvexSnow, preset.sunSamples,
                                    settings.seed, std::uint64_t(l), rampPart, S);
                    }
                }
                if (!gathering && !tracedCarrier) {
                    skyInRamp(scene, c, facing, index, rampOfThickConvexSnow, marcher, S);
                    limbCarriedInRamp(scene, topo, c, carrier, facing, index, density, marcher, sunAt, limbSkins, S);
                }
                perLeaf[l].add(it.pos(), S);
            }
        }
    });
    // The second block adds at most a value per voxel near the carried ones or holding snow.
    LeafValues carried(std::move(perLeaf), nearCarried.activeVoxelCount() + medium.density().activeVoxelCount());
    out.at = std::make_shared<openvdb::Int32Tree>(-1);
    placeValues(carried, leaves, *out.at);
    // Then: one voxel further out, and thin snow on its own.
    perLeaf = Blocks(leaves.leafCount());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> carriedSlot(*out.at);
        TracedIndex tracedIndex(traced);
        openvdb::tree::ValueAccessor<const openvdb::BoolTree> nearCarriedAt(nearCarried);
        Medium::Accessor density = medium.accessor();
        Medium::ColumnMarcher marcher(medium);
        WorkCheck work(progress);
        for (std::size_t l = range.begin(); l != range.end(); ++l)
            for (auto it = leaves.leaf(l).cbeginValueOn(); it; ++it) {
                work.add(WorkCheck::kVoxel);
                const openvdb::Coord c = it.getCoord();
                if (index.getValue(c) >= 0 || carriedSlot.getValue(c) >= 0) continue;
                const bool mayBeNear = nearCarriedAt.isValueOn(c), snow = density.getValue(c) > 0.0f;
                if (!mayBeNear && !snow) continue;  // no value
                if (gathering && !snow && !besideSnow(density, c)) continue;
                Source S;
                const bool near = mayBeNear && average(c, [&](const openvdb::Coord &n) {
                    return carriedSlot.getValue(n) >= 0 && (index.getValue(n) < 0 || tracedIndex.getValue(n) >= 0); },
                                          [&](const openvdb::Coord &n) { return carried[carriedSlot.getValue(n)]; },
                                          S);
                if (!near && snow) {
                    const glm::dvec3 centre = medium.voxelCentre(c);
                    for (std::size_t b = 0; b < beamCount(scene); ++b) {
                        const glm::dvec3 beam = glm::dvec3(beamAt(scene, b, centre, preset.sunSamples, settings.seed,
                                                                  std::uint64_t(l), marcher).irradiance) *
                                                optics.albedo * kInvFourPi;
                        S.addPeak(beam, crossingAnisotropy(optics.g), -towardsBeam(scene, b, centre));
                    }
                }
                if (near || snow) perLeaf[l].add(it.pos(), S);
            }
    });
    out.beyond.emplace(std::move(carried), std::move(perLeaf));
    placeValues(*out.beyond, leaves, *out.at);
    return out;
}

namespace {

// Grid k of BakedGrids (l0, then l1's x, y and z) at the density's resolution.
openvdb::Vec3fTree::Ptr sourceTree(const GridValues &values, const SnowTopology &topo, const SourceValues &source,
                                   const MonteCarloVoxels &traced, int k, const SubProgress &progress) {
    auto tree = std::make_shared<openvdb::Vec3fTree>(*values.topology, openvdb::Vec3f(0.0f), openvdb::TopologyCopy());
    openvdb::tree::LeafManager<openvdb::Vec3fTree> leaves(*tree);  // in the topology's leaf order
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        TracedIndex tracedIndex(traced);
        WorkCheck work(progress);
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            auto &leaf = leaves.leaf(l);
            work.add(WorkCheck::kVoxel * leaf.onVoxelCount());
            for (auto it = leaf.beginValueOn(); it; ++it) {
                const openvdb::Coord c = it.getCoord();
                if (const std::int32_t i = index.getValue(c); i >= 0 && tracedIndex.getValue(c) < 0)
                    it.setValue(k < 4 ? broadComponent(source.broad[i], k) : sourceComponent(source[i], k));
            }
            const LeafValues &beyond = *values.beyond;
            beyond.forEachIn(l, [&](std::size_t m) {
                leaf.setValueOnly(beyond.values[m].offset, k < 4 ? broadComponent(beyond.values[m].lobe, k)
                                                                : sourceComponent(beyond[m], k));
            });
        }
    });
    return tree;
}

// What every grid of a bake carries: the extinction per density the bake used (m^2/kg), its settings, the version.
void insertBakeMetadata(openvdb::GridBase &grid, double extinctionPerDensity, const BakeSettings &settings) {
    grid.insertMeta("firn_extinction_per_density", openvdb::DoubleMetadata(extinctionPerDensity));
    grid.insertMeta("firn_bake_quality", openvdb::StringMetadata(settings.quality == BakeQuality::Draft   ? "DRAFT"
                                                                 : settings.quality == BakeQuality::Final ? "FINAL"
                                                                                                          : "REFERENCE"));
    grid.insertMeta("firn_bake_seed", openvdb::Int64Metadata(openvdb::Int64(settings.seed)));
    grid.insertMeta("firn_version", openvdb::StringMetadata(kVersion));
}

}  // namespace

// Grid k of BakedGrids from its tree, `scale` times the voxel size of `density`, for optics of extinction
// `extinctionPerDensity` (m^2/kg).
openvdb::Vec3fGrid::Ptr sourceGrid(openvdb::Vec3fTree::Ptr tree, int k, int scale, const openvdb::FloatGrid &density,
                                   double extinctionPerDensity, const BakeSettings &settings) {
    auto grid = openvdb::Vec3fGrid::create(std::move(tree));
    grid->setTransform(density.transform().copy());
    if (scale > 1) grid->transform().preScale(double(scale));
    grid->setName(BakedGrids::kNames[k]);
    grid->setVectorType(openvdb::VEC_INVARIANT);
    grid->insertMeta("firn_units", openvdb::StringMetadata("W/m^2/sr (source function: emission / extinction)"));
    insertBakeMetadata(*grid, extinctionPerDensity, settings);
    return grid;
}

// No ring of zeros: Cycles reads a float grid's edge exactly (cycles-volumes.md), tapering to the zero beyond.
openvdb::FloatGrid::Ptr scatterGrid(openvdb::FloatTree::Ptr scattered, const openvdb::FloatGrid &density,
                                    double extinctionPerDensity, const BakeSettings &settings) {
    auto grid = openvdb::FloatGrid::create(std::move(scattered));
    grid->setTransform(density.transform().copy());
    grid->transform().preScale(double(BakedGrids::kScatterScale));
    grid->setName(BakedGrids::kScatterName);
    grid->insertMeta("firn_units", openvdb::StringMetadata("kg/m^3 (the density the renderer scatters)"));
    grid->insertMeta("firn_scatter_optical_depth", openvdb::DoubleMetadata(BakedGrids::kScatterOpticalDepth));
    insertBakeMetadata(*grid, extinctionPerDensity, settings);
    return grid;
}

// The source grids at `scale` times the density's voxel size. At the density's resolution each grid is built
// before the next; coarser, all six are coarsened together from the values directly (coarsenedSources), none
// built at the density's resolution.
BakedGrids makeGrids(const Scene &scene, const SnowTopology &topo, const SourceValues &source,
                     const MonteCarloVoxels &traced, const Preset &preset, const BakeSettings &settings, int scale,
                     const SubProgress &progress) {
    GridValues values = gridValues(scene, topo, source, traced, preset, settings, false, progress);
    BakedGrids out;
    if (scale == 1) {
        values.at = nullptr;  // only the coarsening's readers (BakedValuesSampler) read it
        for (int k = 0; k < int(BakedGrids::kCount); ++k)
            out.source[k] = sourceGrid(sourceTree(values, topo, source, traced, k, progress), k, scale,
                                       scene.medium->density(), scene.medium->optics().extinctionPerDensity, settings);
        return out;
    }
    const auto newReader = [&] {
        return [baked = std::make_shared<BakedValuesSampler>(topo, source, traced, values)](const openvdb::Coord &c) {
            return sourceComponents(baked->at(c));
        };
    };
    auto trees = coarsenedSources(*values.topology, newReader, scene.medium->density().tree(), scale, progress);
    for (int k = 0; k < int(BakedGrids::kCount); ++k)
        out.source[k] = sourceGrid(std::move(trees[k]), k, scale, scene.medium->density(),
                                   scene.medium->optics().extinctionPerDensity, settings);
    return out;
}

}  // namespace firn::bake
