#include "firn/util/openvdb_library.h"

#include <openvdb/openvdb.h>

namespace firn {

void initializeOpenVdb() {
    // Idempotent and thread-safe by itself. Not wrapped in std::call_once: OpenVDB calls call_once inside,
    // and libstdc++'s call_once state is one per thread, so nesting them breaks the inner one.
    openvdb::initialize();
}

}  // namespace firn
