#pragma once

// numpy (N, 3) arrays <-> firn::TriangleMesh, shared by every binding that takes geometry.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "firn/geometry/mesh.h"

namespace firncore {

using FloatArray = pybind11::array_t<float, pybind11::array::c_style | pybind11::array::forcecast>;
using IndexArray = pybind11::array_t<unsigned, pybind11::array::c_style | pybind11::array::forcecast>;

// Validates shapes ((N, 3) vertices in m, (M, 3) triangle indices) and builds a mesh; `what` names the
// input in error messages.
firn::TriangleMesh meshFromArrays(const FloatArray &vertices, const IndexArray &triangles, const char *what);

// An empty mesh when `arrays` is None, else meshFromArrays of its (vertices, triangles).
firn::TriangleMesh optionalMesh(const pybind11::object &arrays, const char *what);

}  // namespace firncore
