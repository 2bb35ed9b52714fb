#pragma once

// One binding function per concept; firncore.cpp calls them in order.
#include <pybind11/pybind11.h>

namespace firncore {
void bindBasics(pybind11::module_ &m);  // errors, Progress, threads
void bindBake(pybind11::module_ &m);    // optics, lights, bake, reference tools
}  // namespace firncore
