// firncore: the Python face of Firn's core. Thin by design: argument conversion, GIL release,
// exception translation. All physics lives in cpp/firn/.
#include "bindings.h"
#include "firn/util/version.h"

PYBIND11_MODULE(firncore, m) {
    m.doc() = "Firn's core: physically based snow, independent of Blender.";
    m.attr("__version__") = firn::kVersion;
    firncore::bindUtil(m);
    firncore::bindOptics(m);
    firncore::bindSnow(m);
    firncore::bindTransport(m);
    firncore::bindGrains(m);
    firncore::bindSpray(m);
    firncore::bindStructure(m);
    firncore::bindIo(m);
}
