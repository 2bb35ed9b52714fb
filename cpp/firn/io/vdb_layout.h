#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace firn {

// Checks the layout of a VDB file against its size before OpenVDB reads it: OpenVDB trusts every length and
// offset it reads (a corrupted string length makes it allocate gigabytes) and, in Debian's build, asserts on
// some corrupted grid metadata (an abort nobody can catch), and OpenVDB 10 reads an uncompressed chunk of the
// length the file gives before checking it (a heap overflow). This walks what OpenVDB reads, in its order:
// the header, the file metadata, each grid's descriptor, compression flags, metadata (its delayed-load table
// must match the tree), transform and tree (nodes, masks, the length of every compressed chunk), and checks
// each length and offset against the bytes that remain. It never decompresses voxels.

struct VdbGridLayout {
    std::string uniqueName;   // as stored: "density", or "name\x1e0" when names repeat
    std::string type;         // "Tree_float_5_4_3"
    std::uint64_t gridBytes;  // from the grid's start to its end (metadata, transform, topology, voxels)
};

struct VdbLayout {
    std::uint64_t fileBytes = 0;
    std::uint32_t formatVersion = 0;
    std::vector<VdbGridLayout> grids;
};

enum class VdbCheck {
    Header,  // header, metadata, descriptors and offsets: a few kilobytes, finds a truncated file
    Trees,   // and every grid's tree, down to the length of each leaf's voxel data: reads the masks of the file
};

// Throws ReadError naming `path` and what is wrong ("... of 4294967040 bytes where 80 remain").
VdbLayout checkVdbLayout(const std::string &path, VdbCheck depth);

}  // namespace firn
