#pragma once

namespace firn {

// Opens OpenVDB's library (grid types, codecs) once; every core entry point that touches grids calls it.
void initializeOpenVdb();

}  // namespace firn
