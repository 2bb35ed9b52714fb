#include "firn/transport/bounce_tail.h"

#include <memory>

#include <gtest/gtest.h>

namespace firn {

namespace {

// Two surface patches of 1 m^2 (unknowns 0 and 1) and one voxel inside the snow (unknown 2).
struct TwoPatches {
    std::shared_ptr<const std::vector<std::int32_t>> slot = std::make_shared<std::vector<std::int32_t>>(
        std::vector<std::int32_t>{0, 1, -1});
    SnowTopology topo;
    TwoPatches() {
        topo.coord.assign(3, openvdb::Coord(0));  // the three in one bounce region
        topo.surfaceSlot = slot;
        topo.patches = SurfaceValues<SurfacePatch>(slot, 2);
        topo.patches.surface(0).area = topo.patches.surface(1).area = 1.0;
    }
    SurfaceValues<glm::vec3> gather(const glm::vec3 &a, const glm::vec3 &b) const {
        SurfaceValues<glm::vec3> values(slot, 2);
        values.surface(0) = a, values.surface(1) = b;
        return values;
    }
};

}  // namespace

// Bounces b, r b, r^2 b, ...: after the second, the rest sums to r^2 b / (1 - r), so the patch holds
// b / (1 - r) in all (geometric series), whatever r per channel.
TEST(BounceTail, CompletesAGeometricSeriesPerChannel) {
    const TwoPatches s;
    const glm::vec3 b(2.0f, 1.0f, 4.0f), r(0.5f, 0.25f, 0.75f);
    const auto before = s.gather(b, 3.0f * b);
    auto last = s.gather(b + r * b, 3.0f * (b + r * b));
    addBounceTail(s.topo, nullptr, before, last);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(last[0][c], b[c] / (1.0f - r[c]), 1e-5f * b[c]) << c;
        EXPECT_NEAR(last[1][c], 3.0f * b[c] / (1.0f - r[c]), 3e-5f * b[c]) << c;
    }
    EXPECT_EQ(last[2], glm::vec3(0.0f));  // inside the snow: no patch
}

// Two regions whose bounces return different shares (a dense cluster 0.75, a lone piece 0.25) each complete
// their own geometric series: one share over both (area-weighted, 0.6 here) gave the cluster b / 0.4 for b / 0.25.
TEST(BounceTail, CompletesEachRegionsOwnSeries) {
    TwoPatches s;
    s.topo.coord[1] = openvdb::Coord(4 << kBounceRegionLog2, 0, 0);  // four regions away
    const float cluster = 0.75f, lone = 0.25f;
    const auto before = s.gather(glm::vec3(4.0f), glm::vec3(2.0f));
    auto last = s.gather(glm::vec3(4.0f + 4.0f * cluster), glm::vec3(2.0f + 2.0f * lone));
    addBounceTail(s.topo, nullptr, before, last);
    EXPECT_NEAR(last[0].x, 4.0f / (1.0f - cluster), 1e-4f);
    EXPECT_NEAR(last[1].x, 2.0f / (1.0f - lone), 1e-5f);
}

// The bounce before the last is the difference of the two gathers before it.
TEST(BounceTail, MeasuresTheShareFromTheLastTwoBounces) {
    const TwoPatches s;
    const auto older = s.gather(glm::vec3(1.0f), glm::vec3(1.0f));
    const auto before = s.gather(glm::vec3(3.0f), glm::vec3(3.0f));  // bounce 2
    auto last = s.gather(glm::vec3(3.5f), glm::vec3(3.5f));           // bounce 0.5: r = 0.25
    addBounceTail(s.topo, &older, before, last);
    EXPECT_NEAR(last[0].x, 3.5f + 0.5f * 0.25f / 0.75f, 1e-5f);
}

// Where two passes' fits make one patch's last bounce negative (the scene's r still positive), the tail adds
// nothing there: scaled by r / (1 - r) = 4 it made that patch's light negative (0.6 - 0.4 * 4 = -1).
TEST(BounceTail, NeverTakesLightFromAPatch) {
    const TwoPatches s;
    const auto before = s.gather(glm::vec3(1.0f), glm::vec3(1.0f));
    auto last = s.gather(glm::vec3(3.0f), glm::vec3(0.6f));  // bounces +2 and -0.4 after 2: r = 1.6 / 2 = 0.8
    addBounceTail(s.topo, nullptr, before, last);
    EXPECT_NEAR(last[0].x, 3.0f + 2.0f * 4.0f, 1e-4f);
    EXPECT_EQ(last[1].x, 0.6f);
}

// A share of 1 or more (the passes not converging as a series) is held at kMaxBounceShare; none without a
// bounce before.
TEST(BounceTail, HoldsTheShareBelowOne) {
    const TwoPatches s;
    const auto before = s.gather(glm::vec3(1.0f), glm::vec3(1.0f));
    auto last = s.gather(glm::vec3(3.0f), glm::vec3(3.0f));  // bounce 2 after 1
    addBounceTail(s.topo, nullptr, before, last);
    EXPECT_NEAR(last[0].x, 3.0f + 2.0f * kMaxBounceShare / (1.0 - kMaxBounceShare), 1e-4f);
    auto first = s.gather(glm::vec3(0.5f), glm::vec3(0.5f));  // nothing gathered before: no share to measure
    addBounceTail(s.topo, nullptr, s.gather(glm::vec3(0.0f), glm::vec3(0.0f)), first);
    EXPECT_EQ(first[0].x, 0.5f);
}

}  // namespace firn
