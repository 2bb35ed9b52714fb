#pragma once

// One binding function per core folder (cpp/firn/<folder>/ -> bind_<folder>.cpp); firncore.cpp calls them
// in layer order.
#include <pybind11/pybind11.h>

namespace firncore {
void bindUtil(pybind11::module_ &m);       // errors, Progress, threads
void bindOptics(pybind11::module_ &m);     // snow optics, KZ04 albedos, ice and water absorption
void bindSnow(pybind11::module_ &m);       // Add Snow Layer
void bindTransport(pybind11::module_ &m);  // lights, bake, reference tools
void bindIo(pybind11::module_ &m);         // reading grids back
}  // namespace firncore
