// The gathering's and the grids' values are built leaf by leaf in parallel and then joined (VoxelValues::appendAll):
// joined, they must read as the values given, in order, peaked lobes at their places.
#include "firn/transport/bake_grid_values.h"

#include <cstddef>
#include <map>
#include <utility>
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

// joined[k] against the k-th value given (the definition): its offset, broad lobe and peaked lobe.
void expectValues(const VoxelValues &joined, const std::vector<std::pair<openvdb::Index, Source>> &given) {
    ASSERT_EQ(joined.values.size(), given.size());
    std::size_t peaks = 0;
    for (std::size_t k = 0; k < given.size(); ++k) {
        EXPECT_EQ(joined.values[k].offset, given[k].first) << k;
        const Source a = joined[k], &b = given[k].second;
        EXPECT_EQ(a.l0, b.l0) << k;
        EXPECT_EQ(a.l1, b.l1) << k;
        EXPECT_EQ(a.peak0, b.peak0) << k;
        EXPECT_EQ(a.peak1, b.peak1) << k;
        peaks += PeakedLobes::holds(b);
    }
    EXPECT_EQ(joined.peaked.peaks().size(), peaks);
}

}  // namespace

TEST(VoxelValues, BlocksAppendedTogetherReadAsTheirValuesInOrder) {
    // Blocks of several sizes, an empty one among them, enough for the copies to run on both threads; appended
    // after values already held, as the grids' second block is.
    const std::vector<std::size_t> sizes{5, 0, 130, 1, 64, 200, 7};
    std::vector<std::pair<openvdb::Index, Source>> given;
    VoxelValues joined;
    std::vector<VoxelValueBlock> first(1);
    for (std::size_t v = 0; v < 4; ++v)
        first[0].add(openvdb::Index(v), sourceOf(99, v)), given.emplace_back(openvdb::Index(v), sourceOf(99, v));
    joined.appendAll(std::move(first));
    std::vector<VoxelValueBlock> blocks(sizes.size());
    for (std::size_t b = 0; b < sizes.size(); ++b)
        for (std::size_t v = 0; v < sizes[b]; ++v) {
            blocks[b].add(openvdb::Index(v % 512), sourceOf(b, v));
            given.emplace_back(openvdb::Index(v % 512), sourceOf(b, v));
        }
    const std::vector<std::size_t> start = joined.appendAll(std::move(blocks));
    ASSERT_EQ(start.size(), sizes.size() + 1);
    std::size_t expected = 4;
    for (std::size_t b = 0; b < sizes.size(); ++b) {
        EXPECT_EQ(start[b], expected) << b;
        expected += sizes[b];
    }
    EXPECT_EQ(start.back(), expected);
    expectValues(joined, given);
}

// The source function's and the grids' peaked lobes are found per block in parallel and joined
// (PeakedLobes::appendAll): joined, every key must read the peak given for it, gaps of many bitmap
// words between keys, a block starting inside the last word already held and empty blocks included.
TEST(PeakedLobes, BlocksAppendedTogetherReadEachPeakAtItsKey) {
    // The definition: a map from key to peak. Appended in two calls (the second's first block starting inside the
    // last word the first filled), with gaps of many bitmap words between keys and empty blocks.
    const auto peakAt = [](std::size_t key) {
        return PeakedLobes::Peak{std::uint32_t(key), glm::vec3(float(key)), glm::vec3(1.0f, float(key % 7), 2.0f)};
    };
    std::map<std::size_t, PeakedLobes::Peak> definition;
    PeakedLobes joined;
    const PeakedLobes::Peaks before{peakAt(3), peakAt(40)};
    joined.appendAll(before);
    for (const PeakedLobes::Peak &peak : before) definition[peak.key] = peak;
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
            definition[shift[b] + key] = peakAt(shift[b] + key);
        }
        pointers.push_back(&blocks[b]);
    }
    joined.appendAll(pointers, shift);
    ASSERT_EQ(joined.peaks().size(), definition.size());
    auto expected = definition.begin();
    for (std::size_t k = 0; k < joined.peaks().size(); ++k, ++expected)
        EXPECT_EQ(joined.peaks()[k].key, expected->first) << k;  // in key order
    Source broad;
    broad.l0 = glm::vec3(0.5f);
    for (std::size_t key = 0; key <= definition.rbegin()->first + 130; ++key) {
        const Source S = joined.with(broad, key);
        ASSERT_EQ(S.l0, broad.l0) << key;
        const auto it = definition.find(key);
        ASSERT_EQ(S.peak0, it == definition.end() ? glm::vec3(0.0f) : it->second.peak0) << key;
        ASSERT_EQ(S.peak1, it == definition.end() ? glm::vec3(0.0f) : it->second.peak1) << key;
    }
}

}  // namespace firn::bake
