#pragma once

#include <array>
#include <cstdint>

#include "firn/util/unwritten_vector.h"

namespace firn {

// Per unknown, its neighbours -x, +x, -y, +y, -z, +z: another unknown's index, or negative for none (the topology's
// boundary face -1 - face, SnowTopology::link; the solver's Stencil::kNone). One table read three ways: the topology
// holds it, the solver's finest level and the assembly's shared links read it in place.
// Sized unwritten: whoever sizes a table writes every row, in parallel.
using VoxelLinks = UnwrittenVector<std::array<std::int32_t, 6>>;

}  // namespace firn
