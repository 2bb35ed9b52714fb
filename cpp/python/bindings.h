#pragma once

// One binding function per concept; firncore.cpp calls them in order.
#include <pybind11/pybind11.h>

namespace firncore {
void bindBasics(pybind11::module_ &m);     // errors, Progress, threads
void bindOptics(pybind11::module_ &m);     // snow optics, KZ04 albedos, ice and water absorption
void bindSnowLayer(pybind11::module_ &m);  // Add Snow Layer
void bindBake(pybind11::module_ &m);       // lights, bake, reference tools
void bindVdb(pybind11::module_ &m);        // reading grids back
}  // namespace firncore
