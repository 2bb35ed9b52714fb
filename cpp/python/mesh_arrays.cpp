#include "mesh_arrays.h"

#include <string>

#include "firn/util/error.h"

namespace py = pybind11;

namespace firncore {

namespace {
void requireRows3(const py::array &a, const char *what, const char *part) {
    if (a.ndim() != 2 || a.shape(1) != 3)
        throw firn::InvalidArgument(std::string(what) + ": " + part + " must be an (N, 3) array");
}
}  // namespace

firn::TriangleMesh meshFromArrays(const FloatArray &vertices, const IndexArray &triangles, const char *what) {
    requireRows3(vertices, what, "vertices");
    requireRows3(triangles, what, "triangles");
    return firn::makeTriangleMesh(vertices.data(), vertices.shape(0), triangles.data(), triangles.shape(0));
}

firn::TriangleMesh optionalMesh(const py::object &arrays, const char *what) {
    if (arrays.is_none()) return {};
    const auto pair = arrays.cast<py::tuple>();
    if (pair.size() != 2) throw firn::InvalidArgument(std::string(what) + " must be (vertices, triangles)");
    return meshFromArrays(pair[0].cast<FloatArray>(), pair[1].cast<IndexArray>(), what);
}

}  // namespace firncore
