// The gathering's and the grids' values are built leaf by leaf in parallel and then joined (VoxelValues::appendAll):
// joined, they must read as the same values added one by one, peaked lobes at the same places.
#include "firn/transport/bake_grid_values.h"

#include <cstddef>
#include <vector>

#include <gtest/gtest.h>

namespace firn::bake {

namespace {

// Value v of block b: a broad lobe and, for every third value, a peaked lobe, all telling b and v apart.
Source sourceOf(std::size_t b, std::size_t v) {
    Source S;
    S.l0 = glm::vec3(float(b), float(v), 1.0f);
    S.l1[0] = glm::vec3(float(b + v));
    if (v % 3 == 1) S.peak0 = glm::vec3(float(10 * b + v)), S.peak1 = glm::vec3(0.0f, 0.0f, float(v + 1));
    return S;
}

void expectSame(const VoxelValues &joined, const VoxelValues &added) {
    ASSERT_EQ(joined.values.size(), added.values.size());
    ASSERT_EQ(joined.peaked.peaks().size(), added.peaked.peaks().size());
    for (std::size_t k = 0; k < added.values.size(); ++k) {
        EXPECT_EQ(joined.values[k].offset, added.values[k].offset) << k;
        const Source a = joined[k], b = added[k];
        EXPECT_EQ(a.l0, b.l0) << k;
        EXPECT_EQ(a.l1, b.l1) << k;
        EXPECT_EQ(a.peak0, b.peak0) << k;
        EXPECT_EQ(a.peak1, b.peak1) << k;
    }
}

}  // namespace

TEST(VoxelValues, BlocksAppendedTogetherReadAsTheirValuesAddedOneByOne) {
    // Blocks of several sizes, an empty one among them, enough for the copies to run on both threads; appended
    // after values already held, as the grids' second block is.
    const std::vector<std::size_t> sizes{5, 0, 130, 1, 64, 200, 7};
    VoxelValues joined, added;
    for (std::size_t v = 0; v < 4; ++v) joined.add(openvdb::Index(v), sourceOf(99, v)), added.add(openvdb::Index(v), sourceOf(99, v));
    std::vector<VoxelValues> blocks(sizes.size());
    for (std::size_t b = 0; b < sizes.size(); ++b)
        for (std::size_t v = 0; v < sizes[b]; ++v) {
            blocks[b].add(openvdb::Index(v % 512), sourceOf(b, v));
            added.add(openvdb::Index(v % 512), sourceOf(b, v));
        }
    const std::vector<std::size_t> start = joined.appendAll(std::move(blocks));
    ASSERT_EQ(start.size(), sizes.size() + 1);
    std::size_t expected = 4;
    for (std::size_t b = 0; b < sizes.size(); ++b) {
        EXPECT_EQ(start[b], expected) << b;
        expected += sizes[b];
    }
    EXPECT_EQ(start.back(), expected);
    expectSame(joined, added);
}

// The source function's and the grids' peaked lobes are found per block in parallel and joined
// (PeakedLobes::appendAll): joined, every key must read the peak it would have pushed one by one, gaps of many bitmap
// words between keys, a block starting inside the last word already held and empty blocks included.
TEST(PeakedLobes, BlocksAppendedTogetherReadAsPeaksPushedOneByOne) {
    const auto peakAt = [](std::size_t key) {
        return PeakedLobes::Peak{std::uint32_t(key), glm::vec3(float(key)), glm::vec3(1.0f, float(key % 7), 2.0f)};
    };
    PeakedLobes joined, pushed;
    for (std::size_t key : {3, 40}) joined.push(peakAt(key)), pushed.push(peakAt(key));
    // Block b's keys relative to its shift; the first block's first key (50) shares word 0 with key 40.
    const std::vector<std::vector<std::size_t>> keys{{0, 1, 77}, {}, {5, 4000, 300000}, {0}, {63, 64, 65, 900000}};
    const std::vector<std::size_t> shift{50, 400000, 400000, 800000, 800001};
    std::vector<PeakedLobes::Peaks> blocks(keys.size());
    std::vector<const PeakedLobes::Peaks *> pointers;
    for (std::size_t b = 0; b < keys.size(); ++b) {
        for (const std::size_t key : keys[b]) {
            PeakedLobes::Peak relative = peakAt(shift[b] + key);
            relative.key = std::uint32_t(key);
            blocks[b].push_back(relative);
            pushed.push(peakAt(shift[b] + key));
        }
        pointers.push_back(&blocks[b]);
    }
    joined.appendAll(pointers, shift);
    ASSERT_EQ(joined.peaks().size(), pushed.peaks().size());
    for (std::size_t k = 0; k < pushed.peaks().size(); ++k)
        EXPECT_EQ(joined.peaks()[k].key, pushed.peaks()[k].key) << k;
    const std::size_t last = pushed.peaks().back().key;
    Source broad;
    broad.l0 = glm::vec3(0.5f);
    std::size_t held = 0;
    for (std::size_t key = 0; key <= last + 130; ++key) {
        const Source a = joined.with(broad, key), b = pushed.with(broad, key);
        ASSERT_EQ(a.peak0, b.peak0) << key;
        ASSERT_EQ(a.peak1, b.peak1) << key;
        held += PeakedLobes::holds(b);
    }
    EXPECT_EQ(held, pushed.peaks().size());  // every peak was read at its key
}

}  // namespace firn::bake
