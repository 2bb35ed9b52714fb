#include "mesh_arrays.h"

#include <cmath>

#include "firn/util/error.h"

namespace py = pybind11;

namespace firncore {

namespace {
void requireRows3(const py::array &a, const char *what, const char *part) {
    if (a.ndim() != 2 || a.shape(1) != 3)
        throw firn::InvalidArgument(std::string(what) + ": " + part + " must be an (N, 3) array");
}
}  // namespace

FloatArray floatArray(const py::handle &values, const std::string &what) {
    FloatArray array = FloatArray::ensure(values);
    if (!array) throw firn::InvalidArgument(what + " must be an array of numbers");
    return array;
}

IndexArray indexArray(const py::handle &values, const std::string &what) {
    const py::array any = py::array::ensure(values);
    // By type number, not by the dtype object: numpy makes equal dtypes that are other objects (an array read
    // through ctypes, unpickled), and those went through the converting path below (0.015 s per million triangles).
    if (any && any.dtype().num() == py::dtype::of<unsigned>().num()) return IndexArray::ensure(any);
    using Wide = py::array_t<double, py::array::c_style | py::array::forcecast>;
    const Wide wide = Wide::ensure(values);
    if (!wide) throw firn::InvalidArgument(what + " must be an array of vertex indices");
    const double *v = wide.data();
    for (py::ssize_t i = 0; i < wide.size(); ++i)
        if (!(v[i] >= 0.0 && v[i] <= 4294967295.0 && v[i] == std::floor(v[i])))
            throw firn::InvalidArgument(what + ": " + std::to_string(v[i]) +
                                        " is not a vertex index (negative, fractional or 2^32 or more)");
    return IndexArray::ensure(wide);
}

firn::TriangleMesh meshFromArrays(const py::handle &vertices, const py::handle &triangles, const char *what) {
    const FloatArray points = floatArray(vertices, std::string(what) + ": vertices");
    const IndexArray indices = indexArray(triangles, std::string(what) + ": triangles");
    requireRows3(points, what, "vertices");
    requireRows3(indices, what, "triangles");
    return firn::makeTriangleMesh(points.data(), points.shape(0), indices.data(), indices.shape(0));
}

firn::TriangleMesh optionalMesh(const py::object &arrays, const char *what) {
    if (arrays.is_none()) return {};
    const py::sequence pair = itemsOf(arrays, 2, what, "(vertices, triangles)");
    return meshFromArrays(pair[0], pair[1], what);
}

py::sequence itemsOf(const py::handle &object, std::size_t size, const std::string &what, const char *form) {
    if (!py::isinstance<py::sequence>(object) || py::isinstance<py::str>(object) || py::len(object) != size)
        throw firn::InvalidArgument(what + " must be " + form);
    return py::reinterpret_borrow<py::sequence>(object);
}

DoubleArray rgbRows(const std::vector<firn::Rgb> &values) {
    DoubleArray out({pybind11::ssize_t(values.size()), pybind11::ssize_t(3)});
    auto view = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < values.size(); ++i)
        for (int c = 0; c < 3; ++c) view(i, c) = values[i][c];
    return out;
}

}  // namespace firncore
