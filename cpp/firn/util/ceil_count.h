#pragma once

#include <cmath>

namespace firn {

// ceil(x) as a count from 1 to `most`, clamped while a double: a huge x (a spray emitter moved 1e30 m, spray seeds
// 42 and 46 under UBSan) overflowed the int it was converted to first (undefined behaviour). NaN counts 1.
inline int ceilCount(double x, int most) {
    if (!(x > 1.0)) return 1;
    return x < most ? int(std::ceil(x)) : most;
}

}  // namespace firn
