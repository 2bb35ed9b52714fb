#include "firn/transport/voxel_blocks.h"

#include <algorithm>
#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

namespace firn {

namespace {

using Voxels = UnwrittenVector<openvdb::Coord>;

// A third of the voxels of [-20, 20)^3 (seeded), in the order OpenVDB visits them: leaf by leaf.
Voxels leafOrdered() {
    openvdb::BoolTree tree(false);
    std::mt19937 random(7);
    for (int x = -20; x < 20; ++x)
        for (int y = -20; y < 20; ++y)
            for (int z = -20; z < 20; ++z)
                if (random() % 3 == 0) tree.setValueOn(openvdb::Coord(x, y, z));
    Voxels out;
    for (auto it = tree.cbeginValueOn(); it; ++it) out.push_back(it.getCoord());
    return out;
}

openvdb::Coord blockOf(const openvdb::Coord &c) {
    const auto half = [](int v) { return v >= 0 ? v / 2 : -((-v + 1) / 2); };
    return openvdb::Coord(half(c.x()), half(c.y()), half(c.z()));
}

// The blocks by their definition: numbered as their first voxel comes, their voxels in order.
VoxelBlocks firstAppearance(const Voxels &voxels) {
    VoxelBlocks out;
    std::map<std::tuple<int, int, int>, std::uint32_t> id;
    std::vector<std::vector<std::uint32_t>> members;
    for (std::size_t i = 0; i < voxels.size(); ++i) {
        const openvdb::Coord b = blockOf(voxels[i]);
        const auto [at, fresh] = id.emplace(std::make_tuple(b.x(), b.y(), b.z()), std::uint32_t(out.coord.size()));
        if (fresh) out.coord.push_back(b), members.emplace_back();
        out.ofRow.push_back(at->second);
        members[at->second].push_back(std::uint32_t(i));
    }
    out.membersStart.push_back(0);
    for (const auto &m : members) {
        out.members.insert(out.members.end(), m.begin(), m.end());
        out.membersStart.push_back(std::uint32_t(out.members.size()));
    }
    return out;
}

void expectSame(const VoxelBlocks &a, const VoxelBlocks &b) {
    ASSERT_EQ(a.coord.size(), b.coord.size());
    EXPECT_TRUE(std::equal(a.coord.begin(), a.coord.end(), b.coord.begin()));
    EXPECT_TRUE(std::equal(a.ofRow.begin(), a.ofRow.end(), b.ofRow.begin(), b.ofRow.end()));
    EXPECT_EQ(a.membersStart, b.membersStart);
    EXPECT_EQ(a.members, b.members);
}

}  // namespace

// Leaf-ordered voxels (the bake's) number their blocks leaf by leaf in parallel, and the blocks (the next level) by
// regions of 4; both as the definition numbers them.
TEST(VoxelBlocks, LeafOrderedVoxelsAndTheirBlocksNumberTheirBlocksByRegions) {
    const Voxels voxels = leafOrdered();
    ASSERT_GT(voxels.size(), 20000u);
    EXPECT_EQ(contiguousRegionEdge(voxels), 8);
    const VoxelBlocks blocks = voxelBlocks(voxels);
    expectSame(blocks, firstAppearance(voxels));
    EXPECT_EQ(contiguousRegionEdge(blocks.coord), 4);
    expectSame(voxelBlocks(blocks.coord), firstAppearance(blocks.coord));
}

// Regions of 4 in lexicographic order split the leaves (8^3) but keep each region of 4 whole.
TEST(VoxelBlocks, RegionsOfFourInRowOrderAreNumberedByRegionsOfFour) {
    Voxels voxels = leafOrdered();
    const auto key = [](const openvdb::Coord &c) {
        const openvdb::Coord r(c.x() >> 2, c.y() >> 2, c.z() >> 2);  // GCC's >> floors negative values
        return std::make_tuple(r.x(), r.y(), r.z(), c.x(), c.y(), c.z());
    };
    std::sort(voxels.begin(), voxels.end(), [&](const auto &a, const auto &b) { return key(a) < key(b); });
    EXPECT_EQ(contiguousRegionEdge(voxels), 4);
    expectSame(voxelBlocks(voxels), firstAppearance(voxels));
}

// Shuffled voxels keep no region whole: numbered serially, the same by definition.
TEST(VoxelBlocks, ShuffledVoxelsAreNumberedInOrder) {
    Voxels voxels = leafOrdered();
    std::shuffle(voxels.begin(), voxels.end(), std::mt19937(11));
    EXPECT_EQ(contiguousRegionEdge(voxels), 0);
    expectSame(voxelBlocks(voxels), firstAppearance(voxels));
}

TEST(VoxelBlocks, NoVoxelsNoBlocks) {
    const VoxelBlocks blocks = voxelBlocks(Voxels{});
    EXPECT_TRUE(blocks.coord.empty());
    EXPECT_EQ(blocks.membersStart, std::vector<std::uint32_t>{0});
}

}  // namespace firn
