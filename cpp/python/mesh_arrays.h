#pragma once

// numpy (N, 3) arrays <-> firn::TriangleMesh, shared by every binding that takes geometry.
#include <array>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "firn/geometry/mesh.h"
#include "firn/util/color.h"

namespace firncore {

using FloatArray = pybind11::array_t<float, pybind11::array::c_style | pybind11::array::forcecast>;
using DoubleArray = pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>;
using RgbTuple = std::array<double, 3>;  // also any (x, y, z) triple

inline firn::Rgb rgb(const RgbTuple &t) { return {t[0], t[1], t[2]}; }
inline RgbTuple tuple(const firn::Rgb &c) { return {c.x, c.y, c.z}; }

// Triples (RGB or points, both glm::dvec3) as an (N, 3) float64 array.
DoubleArray rgbRows(const std::vector<firn::Rgb> &values);

using IndexArray = pybind11::array_t<unsigned, pybind11::array::c_style | pybind11::array::forcecast>;

// Any array-like as C-contiguous float32; InvalidArgument naming `what` when it holds no numbers.
FloatArray floatArray(const pybind11::handle &values, const std::string &what);

// Any array-like as uint32 vertex indices; InvalidArgument for what the cast would change (negative,
// fractional, 2^32 or more: numpy would wrap -1 to 4294967295 and 2^32 to 0).
IndexArray indexArray(const pybind11::handle &values, const std::string &what);

// Validates shapes ((N, 3) vertices in m, (M, 3) triangle indices) and builds a mesh; `what` names the
// input in error messages.
firn::TriangleMesh meshFromArrays(const pybind11::handle &vertices, const pybind11::handle &triangles,
                                  const char *what);

// An empty mesh when `arrays` is None, else meshFromArrays of its (vertices, triangles).
firn::TriangleMesh optionalMesh(const pybind11::object &arrays, const char *what);

// The items of a sequence (tuple, list, array; not a string) of `size`; InvalidArgument naming `what` and `form` otherwise.
pybind11::sequence itemsOf(const pybind11::handle &object, std::size_t size, const std::string &what,
                           const char *form);

}  // namespace firncore
