// The face sources of a floating layer's traced voxels (bake_traced_voxels.h, addFaceSources): up to
// kMaxTracedSteps of paths, so Esc must stop them; how a face's collisions split by the trilinear hat
// (MonteCarloReference::faceSourceIn); which faces are lit, and what the air beside them carries (gridValues).
#include <algorithm>
#include <bitset>
#include <cmath>
#include <utility>

#include <gtest/gtest.h>

#include "box_scene.h"
#include "density_grid.h"
#include "firn/transport/bake.h"
#include "firn/transport/bake_grid_values.h"
#include "firn/transport/bake_traced_voxels.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/snow_topology.h"
#include "firn/transport/source_lobe.h"
#include "firn/transport/traced_source.h"
#include "firn/util/error.h"

namespace firn {

namespace {

// A layer one voxel thick, `width` x `width` voxels of sigma_t h `tau` with air above and below, under a sun.
Scene floatingLayer(int width = 4, double tau = 15.0) {
    return test::boxScene(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(width - 1, width - 1, 0)),
                          float(tau / (10.0 * test::kBoxVoxel)), VolumeOptics{10.0, Rgb(0.999), 0.7},
                          glm::dvec3(0.866, 0.0, 0.5));
}

// The voxel's share of a face's collisions (FaceEstimate::shownShare) in a one-voxel layer of sigma_t h `tau`
// amid its own snow, by quadrature: along the normal, t voxels from the air neighbour's centre (the voxel's at 1,
// the opposite neighbour's at 2), the trilinear density's sigma_t h (1 - |1 - t|) and a camera ray at mu to the
// normal (cosine-weighted over mu) colliding at normal optical depth d given a collision within the two voxels,
// density exp(-d / mu) / (mu (1 - exp(-tau / mu))); the voxel's hat there is 1 - |1 - t|, the air neighbour
// carries the rest. Midpoint rule in t and mu.
double shownShareByQuadrature(double tau) {
    constexpr int kT = 4000, kMu = 200;
    double voxel = 0.0, all = 0.0, depth = 0.0;
    for (int i = 0; i < kT; ++i) {
        const double t = (i + 0.5) * 2.0 / kT, sigmaTh = tau * (1.0 - std::abs(1.0 - t)), dt = 2.0 / kT;
        const double d = depth + 0.5 * sigmaTh * dt;  // the normal's optical depth to t
        depth += sigmaTh * dt;
        double density = 0.0;
        for (int j = 0; j < kMu; ++j) {
            const double mu = (j + 0.5) / kMu;
            density += 2.0 * mu * std::exp(-d / mu) / (mu * -std::expm1(-tau / mu)) / kMu;
        }
        const double collisions = sigmaTh * density * dt;
        voxel += collisions * (1.0 - std::abs(1.0 - t)), all += collisions;
    }
    return voxel / all;
}

// What a voxel's value sends towards w, red channel (W/m^2/sr): its broad and peaked lobes (source_lobe.h).
double redToward(const Source &s, const glm::dvec3 &w) {
    return lobeRadiance(s.l0.x, glm::dvec3(s.l1[0]), w) + peakRadiance(glm::dvec3(s.peak0), glm::dvec3(s.peak1), w).x;
}

// The 4 x 4 floatingLayer's voxels, x major.
std::vector<openvdb::Coord> layerVoxels() {
    std::vector<openvdb::Coord> voxels;
    for (int x = 0; x < 4; ++x)
        for (int y = 0; y < 4; ++y) voxels.emplace_back(x, y, 0);
    return voxels;
}

// A 4 x 4 x 4 lump of sigma_t h 8 of forward scattering snow under a sun 30 degrees high from +x.
Scene sunlitLump() {
    return test::boxScene(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(3, 3, 3)),
                          float(8.0 / (10.0 * test::kBoxVoxel)), VolumeOptics{10.0, Rgb(0.999), 0.85},
                          glm::dvec3(0.866, 0.0, 0.5));
}

// The lump's voxels, x major, then y, then z.
std::vector<openvdb::Coord> lumpVoxels() {
    std::vector<openvdb::Coord> voxels;
    for (int x = 0; x < 4; ++x)
        for (int y = 0; y < 4; ++y)
            for (int z = 0; z < 4; ++z) voxels.emplace_back(x, y, z);
    return voxels;
}

// The voxels' sources at `paths` each and their faces' (gatheredVoxelFaces), the faces' paths reporting to
// `faceProgress`.
bake::MonteCarloVoxels tracedWithFaces(const Scene &scene, const std::vector<openvdb::Coord> &voxels, int paths,
                                       const SubProgress &faceProgress = SubProgress(nullptr, 0.0, 1.0)) {
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    const bake::GatheringPlan plan{paths, paths * 1000.0 * double(voxels.size()), paths, std::max(64, paths / 2)};
    bake::MonteCarloVoxels traced = bake::traceSources(scene, voxels, plan.paths, 3, SubProgress(nullptr, 0.0, 1.0));
    bake::addFaceSources(scene, topo, voxels, bake::gatheredVoxelFaces(plan), 5, faceProgress, traced);
    return traced;
}

// The unknowns' source values where every unknown is traced: its traced source.
bake::SourceValues tracedUnknowns(const SnowTopology &topo, const std::vector<openvdb::Coord> &voxels,
                                  const bake::MonteCarloVoxels &traced) {
    bake::SourceValues source;
    source.broad.assign(topo.size(), BroadLobe{});
    bake::PeakedLobes::Peaks peaks;
    for (std::size_t v = 0; v < voxels.size(); ++v)
        if (const std::int32_t i = topo.index->getValue(voxels[v]); i >= 0) {
            source.broad[std::size_t(i)] = traced.source[v];
            bake::PeakedLobes::append(peaks, std::size_t(i), traced.source[v]);
        }
    source.peaked.appendAll(peaks);
    return source;
}

// Every voxel traced (tracedWithFaces at 256 paths) and the grids' values around them as the bake sets them.
struct TracedGrids {
    SnowTopology topo;
    bake::MonteCarloVoxels traced;
    bake::SourceValues source;
    bake::GridValues values;

    TracedGrids(const Scene &scene, const std::vector<openvdb::Coord> &voxels)
        : topo(buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0))),
          traced(tracedWithFaces(scene, voxels, 256)), source(tracedUnknowns(topo, voxels, traced)),
          values(bake::gridValues(scene, topo, source, traced,
                                  bake::Preset{1, 1, 1e-3, 1, 0, 256, 256, false, 0.25, 0.0}, BakeSettings{}, true,
                                  SubProgress(nullptr, 0.0, 1.0))) {}
    // The grids' value at voxel c.
    Source at(const openvdb::Coord &c) const { return bake::BakedValuesSampler(topo, source, traced, values).at(c); }
};

}  // namespace

// Every voxel holds a source for each of its air faces (the rim's sides too); cancelled, the faces' paths stop
// (Cancelled).
TEST(FaceSources, EachTwoSidedVoxelHoldsItsFacesAndEscStopsThem) {
    const Scene scene = floatingLayer();
    const std::vector<openvdb::Coord> voxels = layerVoxels();
    const bake::MonteCarloVoxels traced = tracedWithFaces(scene, voxels, 64);
    ASSERT_EQ(traced.faces.size(), voxels.size());
    for (std::size_t v = 0; v < voxels.size(); ++v) {
        const openvdb::Coord &c = voxels[v];
        const unsigned sides = unsigned(c.x() == 0) | unsigned(c.x() == 3) << 1 | unsigned(c.y() == 0) << 2 |
                               unsigned(c.y() == 3) << 3;
        EXPECT_EQ(traced.faces[std::size_t(traced.facesAt[v])].open, 0b110000u | sides);  // -z, +z and the rim's
    }

    Progress cancelled;
    cancelled.cancel();
    EXPECT_THROW(tracedWithFaces(scene, voxels, 64, SubProgress(&cancelled, 0.0, 1.0)), Cancelled);
}

// A traced layer's voxels (light traced whole: FaceGathering::inLayer) hold a source for each face open to air,
// one-sided too: a 4 x 4 x 3 layer of sigma_t h 2 (the suite's slab_thin) seen from below shows its lower face's
// first optical depth, not its lowest voxels' mean (docs/benchmarks.md, slab-thin). Gathered per voxel (no
// inLayer), a voxel open on one side along each axis gets none, as before.
TEST(FaceSources, ATracedLayersVoxelsHoldTheirOneSidedFaces) {
    const Scene scene = test::boxScene(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(3, 3, 2)),
                                       float(2.0 / (10.0 * test::kBoxVoxel)), VolumeOptics{10.0, Rgb(0.99), 0.6},
                                       glm::dvec3(0.866, 0.0, 0.5));
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    std::vector<openvdb::Coord> voxels;
    for (int x = 0; x < 4; ++x)
        for (int y = 0; y < 4; ++y)
            for (int z = 0; z < 3; ++z) voxels.emplace_back(x, y, z);
    const SubProgress none(nullptr, 0.0, 1.0);
    bake::MonteCarloVoxels traced = bake::traceSources(scene, voxels, 64, 3, none);
    bake::addFaceSources(scene, topo, voxels, {64, 64, 1e12, {}}, 5, none, traced);
    EXPECT_TRUE(traced.faces.empty());
    bake::addFaceSources(scene, topo, voxels, {64, 64, 1e12, std::vector<bool>(voxels.size(), true)}, 5, none, traced);
    for (std::size_t v = 0; v < voxels.size(); ++v) {
        const openvdb::Coord &c = voxels[v];
        unsigned open = 0;  // bit f for face f (-x, +x, -y, +y, -z, +z)
        for (int a = 0; a < 3; ++a)
            open |= unsigned(c[a] == 0) << (2 * a) | unsigned(c[a] == (a < 2 ? 3 : 2)) << (2 * a + 1);
        if (open == 0) {  // the middle voxels: no air face
            EXPECT_EQ(traced.facesAt[v], -1);
            continue;
        }
        ASSERT_GE(traced.facesAt[v], 0);
        EXPECT_EQ(traced.faces[std::size_t(traced.facesAt[v])].open, open);
        for (int f : {4, 5}) {
            if (open >> f & 1u) {
                EXPECT_GT(traced.faces[std::size_t(traced.facesAt[v])].source[f].l0.x, 0.0);
            }
        }
    }
}

// A gathered lump's voxels thicker than 2 optical depths hold a source for each face open to air, one-sided too (a 4 x
// 4 x 4 lump of sigma_t h 8: a camera sees its faces' first optical depth, not the voxels' mean over 8;
// docs/benchmarks.md, spray-lump-faces). Before, only voxels open to air on both faces along an axis gathered their
// faces. Where the faces at their paths would pass the budget (at their own steps per path) they take the fewest;
// where those would too, none.
TEST(FaceSources, AGatheredLumpsThickVoxelsHoldTheirOneSidedFaces) {
    const Scene scene = sunlitLump();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    const std::vector<openvdb::Coord> voxels = lumpVoxels();
    const SubProgress none(nullptr, 0.0, 1.0);
    const bake::GatheringPlan plan{256, 256.0 * 1000.0 * double(voxels.size()), 256, 128};
    bake::MonteCarloVoxels traced = bake::traceSources(scene, voxels, plan.paths, 3, none);
    const bake::FacesTraced taken =
        bake::addFaceSources(scene, topo, voxels, bake::gatheredVoxelFaces(plan), 5, none, traced);
    for (std::size_t v = 0; v < voxels.size(); ++v) {
        const openvdb::Coord &c = voxels[v];
        unsigned open = 0;  // bit f for face f (-x, +x, -y, +y, -z, +z)
        for (int a = 0; a < 3; ++a) open |= unsigned(c[a] == 0) << (2 * a) | unsigned(c[a] == 3) << (2 * a + 1);
        if (open == 0) {
            EXPECT_EQ(traced.facesAt[v], -1);
            continue;
        }
        ASSERT_GE(traced.facesAt[v], 0);
        const bake::FaceSources &faces = traced.faces[std::size_t(traced.facesAt[v])];
        EXPECT_EQ(faces.open, open);
        for (int f = 0; f < 6; ++f) {
            if (open >> f & 1u) {
                EXPECT_GT(faces.source[f].l0.x + faces.source[f].peak0.x, 0.0f);
            }
        }
    }

    const auto facesWithin = [&](double budget) {
        bake::MonteCarloVoxels again = bake::traceSources(scene, voxels, 64, 3, none);
        bake::addFaceSources(scene, topo, voxels, {128, 64, budget, {}}, 5, none, again);
        return again.faces.size();
    };
    ASSERT_EQ(taken.faces, 4u * 4 * 6);  // the lump's faces open to air
    const double perPath = taken.stepsPerPath * double(taken.faces);  // one path on every face
    EXPECT_EQ(facesWithin(perPath * 64 * 1.5), 56u);  // the fewest paths fit: all 56 surface voxels
    EXPECT_EQ(facesWithin(perPath * 64 * 0.5), 0u);
}

// A floating layer's rim voxel shows its cameras below what its top and bottom faces show them, as a middle voxel
// does, not its mean (the sun-lit top's light, forward: at sigma_t h 15 the mean is 46 % brighter seen from below;
// docs/benchmarks.md, float-under). Its side faces, open to air on one side, once turned it to its mean: the
// layer from below 13.1 -> 11.3 % per block (docs/benchmarks.md, float-bisect 2). A corner voxel, whose top and
// bottom lie on no flat layer (3 neighbours of kMinLayerNeighbours 5), keeps its mean.
TEST(FaceSources, AFloatingLayersRimVoxelShowsWhatItsFacesShow) {
    const bake::MonteCarloVoxels traced = tracedWithFaces(floatingLayer(4, 15.0), layerVoxels(), 512);
    const glm::dvec3 below(0.0, 0.0, -1.0);
    const auto shownOverMean = [&](int x, int y) {
        const std::size_t v = std::size_t(x * 4 + y);
        const Source &shown = traced.faces[std::size_t(traced.facesAt[v])].shown;
        return redToward(shown, below) / redToward(traced.source[v], below);
    };
    EXPECT_LT(shownOverMean(1, 1), 0.95);  // a middle voxel (0.87 at these seeds)
    for (const auto &[x, y] : {std::pair{1, 0}, {2, 0}, {1, 3}, {2, 3}, {0, 1}, {0, 2}, {3, 1}, {3, 2}}) {
        EXPECT_LT(shownOverMean(x, y), 0.95) << "rim voxel " << x << ", " << y;  // 0.59-0.85; its mean: 1
    }
    for (const auto &[x, y] : {std::pair{0, 0}, {0, 3}, {3, 0}, {3, 3}}) {
        EXPECT_EQ(shownOverMean(x, y), 1.0) << "corner voxel " << x << ", " << y;
    }
}

// A gathered lump's faces lit by the sun (30 degrees high, from +x) are those facing it that take its beam: +x and
// +z, not the others. The air beside the sunlit top edge carries those faces' sources, weighted as the surface
// voxels around it face it (facingAverage), not the edge voxels' means, which their moments fit reads 0.96 of the
// converged ones towards the sun-lit views at 256 paths (docs/benchmarks.md, spray-air, spray-lit-faces).
TEST(FaceSources, TheAirBesideALumpsSunlitEdgeCarriesItsLitFaces) {
    const std::vector<openvdb::Coord> voxels = lumpVoxels();
    const TracedGrids grids(sunlitLump(), voxels);
    const SnowTopology &topo = grids.topo;
    const bake::MonteCarloVoxels &traced = grids.traced;
    for (std::size_t v = 0; v < voxels.size(); ++v) {
        if (traced.facesAt[v] < 0) continue;
        const bake::FaceSources &faces = traced.faces[std::size_t(traced.facesAt[v])];
        EXPECT_EQ(faces.lit, faces.open & 0b100010u) << "voxel " << voxels[v];  // +x and +z
    }

    const glm::dvec3 w = glm::normalize(glm::dvec3(0.5, 0.0, 0.866));  // towards a camera 60 degrees up
    for (int y = 1; y <= 2; ++y) {
        const openvdb::Coord air(4, y, 4);
        Source expected;  // the faces' sources averaged part by part, as the grids hold them
        float total = 0.0f;
        for (int dy = -1; dy <= 1; ++dy) {  // the edge voxels around it, the only snow within one voxel
            const openvdb::Coord edge(3, y + dy, 3);
            const std::int32_t i = topo.index->getValue(edge);
            const glm::dvec3 offset = glm::normalize(glm::dvec3(1.0, -dy, 1.0));  // from the edge voxel to the air
            const float weight = float(std::max(0.0, glm::dot(topo.patches[std::size_t(i)].normal, offset)));
            const std::size_t v = std::size_t(3 * 16 + (y + dy) * 4 + 3);
            const bake::FaceSources &faces = traced.faces[std::size_t(traced.facesAt[v])];
            expected.add(faces.source[1], 0.5f * weight), expected.add(faces.source[5], 0.5f * weight), total += weight;
        }
        expected.divideBy(total);
        const double carried = redToward(expected, w);
        EXPECT_NEAR(redToward(grids.at(air), w), carried, 1e-5 * carried) << "air " << air;
    }
}

namespace {

// The sunlitLump with a fringe on its sunlit +x side: a layer of sigma_t h 3 at x = 4 (part of the density ramp, not
// an unknown, yet traced and thicker than kMaxDirectionFitTau).
Scene lumpWithFringe() {
    auto grid = test::densityGrid(test::kBoxVoxel);
    const float perTau = float(1.0 / (10.0 * test::kBoxVoxel));  // kg/m^3 for sigma_t h 1 at 10 m^2/kg
    grid->fill(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(3, 3, 3)), 8.0f * perTau);
    grid->fill(openvdb::CoordBBox(openvdb::Coord(4, 0, 0), openvdb::Coord(4, 3, 3)), 3.0f * perTau);
    grid->tree().setValue(openvdb::Coord(5, 0, 1), 0.05f * perTau);  // holds snow, yet too thin for an unknown
    Scene scene;
    scene.medium = std::make_shared<Medium>(grid, VolumeOptics{10.0, Rgb(0.999), 0.85});
    scene.suns = {SunLight{glm::normalize(glm::dvec3(0.866, 0.0, 0.5)), Rgb(1.0), 0.0093}};
    return scene;
}

// lumpWithFringe's traced voxels: the lump's (lumpVoxels), then its fringe's, y major, then the thin voxel.
std::vector<openvdb::Coord> lumpAndFringeVoxels() {
    std::vector<openvdb::Coord> voxels = lumpVoxels();
    for (int y = 0; y < 4; ++y)
        for (int z = 0; z < 4; ++z) voxels.emplace_back(4, y, z);
    voxels.emplace_back(5, 0, 1);
    return voxels;
}

// The fringe voxel's faces open to air: +x and the rim's, not -x against the lump; nor +x where the thin voxel holds
// snow (a traced voxel carries its own value), nor `closed`.
unsigned fringeFacesOpen(const openvdb::Coord &c, unsigned closed = 0) {
    const unsigned rim = unsigned(c.y() == 0) << 2 | unsigned(c.y() == 3) << 3 | unsigned(c.z() == 0) << 4 |
                         unsigned(c.z() == 3) << 5;
    const unsigned plusX = c == openvdb::Coord(4, 0, 1) ? 0u : 0b10u;
    return (plusX | rim) & ~closed;
}

}  // namespace

// A lump's fringe belongs to the density ramp, not to the unknowns, but is traced as the lump's voxels are: it gathers
// its faces open to air too (not the one against the lump, nor one toward traced snow), and a voxel inside its layer
// shows what those faces show (spray_dense over 16 seeds 17.26 -> 16.85 % per block; docs/benchmarks.md,
// spray-lit-cores). A corner has too few neighbours in the layer (kMinLayerNeighbours) and keeps its mean. Before, a
// voxel that was no unknown gathered none. (Brighter toward the sun than the mean does not hold at 256 paths: the
// interior voxels' ratios 0.16-1.49.)
TEST(FaceSources, ALumpsFringeGathersItsFacesOpenToAir) {
    const Scene scene = lumpWithFringe();
    const std::vector<openvdb::Coord> voxels = lumpAndFringeVoxels();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    const bake::MonteCarloVoxels traced = tracedWithFaces(scene, voxels, 256);
    const glm::dvec3 w = glm::normalize(glm::dvec3(0.866, 0.0, 0.5));  // towards a camera by the sun
    for (std::size_t v = 64; v < voxels.size() - 1; ++v) {
        const openvdb::Coord &c = voxels[v];
        ASSERT_LT(topo.index->getValue(c), 0) << "fringe " << c;  // not an unknown
        ASSERT_GE(traced.facesAt[v], 0) << "fringe " << c;
        const bake::FaceSources &faces = traced.faces[std::size_t(traced.facesAt[v])];
        EXPECT_EQ(faces.open, fringeFacesOpen(c)) << "fringe " << c;
        const double shown = redToward(faces.shown, w), mean = redToward(traced.source[v], w);
        const bool corner = (c.y() == 0 || c.y() == 3) && (c.z() == 0 || c.z() == 3);
        const bool interior = c.y() % 3 != 0 && c.z() % 3 != 0;
        if (corner) {
            EXPECT_EQ(shown, mean) << "fringe " << c;  // 3 neighbours in the layer: its mean
        } else if (interior) {
            EXPECT_NE(shown, mean) << "fringe " << c;  // 7 or 8: what its faces show
        }
    }
}

// A fringe on the ground opens no face into it: an occluder between its centre and the one under it closes that face,
// as the topology's (occluderAcross). Before, its face into the ground gathered from under it.
TEST(FaceSources, AFringeOnTheGroundOpensNoFaceIntoIt) {
    Scene scene = lumpWithFringe();
    const float z = float(-0.5 * test::kBoxVoxel);  // between the lowest voxels' centres and those under them
    const float v[] = {-1, -1, z, 1, -1, z, 1, 1, z, -1, 1, z};
    const unsigned t[] = {0, 1, 2, 0, 2, 3};
    scene.occluders = std::make_shared<Occluders>(makeTriangleMesh(v, 4, t, 2), std::vector<Rgb>(2, Rgb(0.5)));
    const std::vector<openvdb::Coord> voxels = lumpAndFringeVoxels();
    const bake::MonteCarloVoxels traced = tracedWithFaces(scene, voxels, 64);
    for (std::size_t f = 64; f < voxels.size() - 1; ++f) {
        const openvdb::Coord &c = voxels[f];
        ASSERT_GE(traced.facesAt[f], 0) << "fringe " << c;
        EXPECT_EQ(traced.faces[std::size_t(traced.facesAt[f])].open, fringeFacesOpen(c, 1u << 4)) << "fringe " << c;
    }
}

// A lump's face toward its traced fringe gathers nothing: the fringe takes its own value there, so no air carries that
// face (faceCarried), though the topology counts it open (the fringe is no unknown). Untraced, the fringe leaves it
// open. spray_dense spent 278 of its unknowns' 507 faces so: closed, the rest 88 -> 128 paths each, over seeds 0-7
// 17.04 -> 16.25 % per block (docs/benchmarks.md, fringe-inner).
TEST(FaceSources, ALumpsFaceTowardItsTracedFringeGathersNothing) {
    const Scene scene = lumpWithFringe();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    const std::vector<openvdb::Coord> lump = lumpVoxels();
    for (const bool fringeTraced : {true, false}) {
        const bake::MonteCarloVoxels traced = tracedWithFaces(scene, fringeTraced ? lumpAndFringeVoxels() : lump, 64);
        for (std::size_t v = 0; v < lump.size(); ++v) {
            if (lump[v].x() != 3) continue;  // beside the fringe
            const std::size_t i = std::size_t(topo.index->getValue(lump[v]));
            ASSERT_TRUE(topo.isAirFace(i, 1)) << lump[v];  // the topology's +x: open
            const bool open = traced.facesAt[v] >= 0 && traced.faces[std::size_t(traced.facesAt[v])].open >> 1 & 1u;
            EXPECT_EQ(open, !fringeTraced) << lump[v];
        }
    }
}

// The air across a lump's fringe's outer face carries that face's source (faceCarried): the Monte Carlo of where the
// face's cameras collide, though that air lies two voxels from the lump's surface unknowns. Before, it took the
// average of its neighbours' values, the fringe's mean among them (docs/benchmarks.md, lump-contrast).
TEST(FaceSources, TheAirPastALumpsFringeCarriesTheFringesOuterFace) {
    const std::vector<openvdb::Coord> voxels = lumpAndFringeVoxels();
    const TracedGrids grids(lumpWithFringe(), voxels);
    const bake::MonteCarloVoxels &traced = grids.traced;
    const glm::dvec3 w = glm::normalize(glm::dvec3(0.866, 0.0, 0.5));  // towards a camera by the sun
    for (int y = 1; y <= 2; ++y)
        for (int z = 1; z <= 2; ++z) {
            const std::size_t v = std::size_t(64 + 4 * y + z);  // the fringe voxel (4, y, z)
            ASSERT_GE(traced.facesAt[v], 0) << voxels[v];
            const double face = redToward(traced.faces[std::size_t(traced.facesAt[v])].source[1], w);  // its +x
            const openvdb::Coord air(5, y, z);
            EXPECT_NEAR(redToward(grids.at(air), w), face, 1e-5 * face) << "air " << air;
        }
}

// Where the budget holds the unknowns' faces at their fewest paths but not the fringe's too, the fringe's drop and the
// unknowns' keep theirs. Before, the fringe's faces made every face drop.
TEST(FaceSources, AFringesFacesDropFirstAtTheBudgetsEdge) {
    const Scene scene = lumpWithFringe();
    const std::vector<openvdb::Coord> voxels = lumpAndFringeVoxels();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    bake::MonteCarloVoxels traced = bake::traceSources(scene, voxels, 64, 3, SubProgress(nullptr, 0.0, 1.0));
    // The lump's faces but its +x (toward the traced fringe); the fringe's +x (but one, toward snow) and its rim's.
    constexpr int kLumpFaces = 5 * 16, kFringeFaces = 15 + 16;
    bake::MonteCarloVoxels all = traced;
    const double perPath = bake::addFaceSources(scene, topo, voxels, {64, 64, 1e12, {}}, 5,
                                                SubProgress(nullptr, 0.0, 1.0), all).stepsPerPath;  // a face's path
    const bake::FaceGathering how{64, 64, perPath * 64.0 * (kLumpFaces + kFringeFaces / 2), {}};
    bake::addFaceSources(scene, topo, voxels, how, 5, SubProgress(nullptr, 0.0, 1.0), traced);
    ASSERT_EQ(traced.facesAt.size(), voxels.size());
    int lumpFaces = 0;
    for (std::size_t v = 0; v < voxels.size(); ++v) {
        if (v >= 64) {
            EXPECT_LT(traced.facesAt[v], 0) << "fringe " << voxels[v];
        } else if (traced.facesAt[v] >= 0) {
            lumpFaces += int(std::bitset<6>(traced.faces[std::size_t(traced.facesAt[v])].open).count());
        }
    }
    EXPECT_EQ(lumpFaces, kLumpFaces);
}

// A gathered lump's lit faces (FaceSources::lit) take kLitFacePaths, its other faces the faces' own: against the same
// faces all at the faces' paths, the lit faces' sources move (their extra paths pooled in) and the others' stay to the
// bit. Before, every face took the faces' paths (docs/benchmarks.md, face-paths).
TEST(FaceSources, ALumpsLitFacesTakeMorePaths) {
    const Scene scene = sunlitLump();
    const std::vector<openvdb::Coord> voxels = lumpVoxels();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    const bake::GatheringPlan plan{128, 128 * 1000.0 * double(voxels.size()), 128, 64, bake::kLitFacePaths};
    bake::FaceGathering how = bake::gatheredVoxelFaces(plan);
    ASSERT_EQ(how.litPaths, bake::kLitFacePaths);
    ASSERT_LT(how.paths, how.litPaths);
    const auto traced = [&](int litPaths) {
        how.litPaths = litPaths;
        bake::MonteCarloVoxels out = bake::traceSources(scene, voxels, plan.paths, 3, SubProgress(nullptr, 0.0, 1.0));
        bake::addFaceSources(scene, topo, voxels, how, 5, SubProgress(nullptr, 0.0, 1.0), out);
        return out;
    };
    const bake::MonteCarloVoxels more = traced(bake::kLitFacePaths), same = traced(0);
    const glm::dvec3 sunward = glm::normalize(glm::dvec3(0.866, 0.0, 0.5));
    int lit = 0, other = 0;
    for (std::size_t v = 0; v < voxels.size(); ++v) {
        ASSERT_EQ(more.facesAt[v], same.facesAt[v]) << voxels[v];
        if (same.facesAt[v] < 0) continue;
        const bake::FaceSources &a = more.faces[std::size_t(more.facesAt[v])];
        const bake::FaceSources &b = same.faces[std::size_t(same.facesAt[v])];
        for (int f = 0; f < 6; ++f) {
            if (!(b.open >> f & 1u)) continue;
            for (const glm::dvec3 &w : {faceNormal(f), sunward}) {
                if (b.lit >> f & 1u) {
                    EXPECT_NE(redToward(a.source[f], w), redToward(b.source[f], w)) << voxels[v] << " face " << f;
                } else {
                    EXPECT_EQ(redToward(a.source[f], w), redToward(b.source[f], w)) << voxels[v] << " face " << f;
                }
            }
            ++(b.lit >> f & 1u ? lit : other);
        }
    }
    EXPECT_GT(lit, 0);
    EXPECT_GT(other, 0);
}

// A lit face's paths: kLitFacePaths where the faces take fewer, within kLitFaceExtraSteps beyond the faces' own.
TEST(FaceSources, LitFacePathsWithinTheirExtraSteps) {
    EXPECT_EQ(bake::litFacePaths(128, bake::kLitFacePaths, 128 * 1000.0), bake::kLitFacePaths);
    EXPECT_EQ(bake::litFacePaths(512, bake::kLitFacePaths, 512 * 1000.0), 512);  // the faces' own are more
    EXPECT_EQ(bake::litFacePaths(128, bake::kLitFacePaths, 0.0), bake::kLitFacePaths);  // no lit face
    // Each path beyond the faces' own costs the lit faces kLitFaceExtraSteps / 100.5 steps: 100 more fit.
    EXPECT_EQ(bake::litFacePaths(128, bake::kLitFacePaths, 128 * bake::kLitFaceExtraSteps / 100.5), 228);
}

// The faces' budget is priced at their own steps per path, measured by a pilot on a few of them (the same every run),
// not at the voxels' pilot's: a lump's face gathers in its first optical depths, and its paths leave sooner than its
// voxel's. With the voxels' paths priced far above the faces' and what they leave of kMaxTracedSteps holding the faces'
// paths at the faces' own price with a tenth to spare, the faces take them all; with a budget for 128.5 paths, 128.
// Before, the faces were priced at the voxels' pilot: spray_dense's at 1336 steps per path against their own 743, 144
// of the 512 paths asked (docs/benchmarks.md, face-share); here none would fit.
TEST(FaceSources, TheFacesArePricedAtTheirOwnStepsPerPath) {
    const Scene scene = sunlitLump();
    const std::vector<openvdb::Coord> voxels = lumpVoxels();
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(nullptr, 0.0, 1.0));
    const SubProgress none(nullptr, 0.0, 1.0);
    const auto faces = [&](const bake::FaceGathering &how) {
        bake::MonteCarloVoxels traced = bake::traceSources(scene, voxels, 64, 3, none);
        return bake::addFaceSources(scene, topo, voxels, how, 5, none, traced);
    };
    const bake::FacesTraced all = faces({256, 64, bake::kMaxTracedSteps, {}});
    ASSERT_EQ(all.paths, 256);
    ASSERT_EQ(all.faces, 4u * 4 * 6);
    const double perPath = all.stepsPerPath * double(all.faces);  // one path on every face
    // The voxels' own pilot: their paths longer than the faces'.
    const bake::GatheringPlan voxelsPlan =
        bake::planGathering(scene, bake::Preset{9, 4, 1e-5, 0, 1, 256, 256, true, 1.0, 0.0}, voxels, 1);
    ASSERT_EQ(voxelsPlan.paths, 256);
    EXPECT_LT(all.stepsPerPath, voxelsPlan.steps / (256.0 * double(voxels.size())));

    const bake::GatheringPlan plan{128, bake::kMaxTracedSteps - 1.1 * 256 * perPath, 128, 256};
    ASSERT_GT(plan.steps / (128.0 * double(voxels.size())), 10.0 * all.stepsPerPath);  // the voxels' price
    const bake::FacesTraced taken = faces(bake::gatheredVoxelFaces(plan));
    EXPECT_EQ(taken.stepsPerPath, all.stepsPerPath);  // the same pilot
    EXPECT_EQ(taken.paths, 256);
    EXPECT_EQ(faces({256, 64, 128.5 * perPath, {}}).paths, 128);
}

// A face's collisions split by the trilinear hat as the quadrature splits them: at sigma_t h 2, where 17 % of them
// lie past the voxel's centre (a middle voxel of a 5 x 5 layer, both faces; 4096 points read 0.5787 against
// 0.5790). Giving the air neighbour only its own hat's share, max(0, 1 - t), would read 0.605 (tried, not kept:
// docs/benchmarks.md "hat-debts").
TEST(FaceSources, AFacesCollisionsSplitByTheHatAsTheQuadratureSplitsThem) {
    constexpr double kTau = 2.0;
    const MonteCarloReference reference(floatingLayer(5, kTau));
    const double expected = shownShareByQuadrature(kTau);
    for (const int face : {4, 5}) {
        const FaceEstimate estimate = reference.faceSourceIn(openvdb::Coord(2, 2, 0), face, 4096, 7, 0);
        EXPECT_NEAR(estimate.shownShare, expected, 0.005) << "face " << face;
    }
}

}  // namespace firn
