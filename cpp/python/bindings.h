#pragma once

// One binding function per core folder (cpp/firn/<folder>/ -> bind_<folder>.cpp); firncore.cpp calls them
// in layer order.
#include <utility>

#include <pybind11/pybind11.h>

#include "firn/util/threads.h"

namespace firncore {

// Every long core call goes through here: without the GIL (Blender's UI keeps running Python meanwhile) and
// inside the core's own TBB arena (Blender's threads never pick up its tasks). `work` must not touch Python
// objects: convert arguments before, build Python results after.
template <class Work>
auto longCall(Work &&work) -> decltype(work()) {
    pybind11::gil_scoped_release release;
    return firn::runInCoreArena(std::forward<Work>(work));
}

void bindUtil(pybind11::module_ &m);       // errors, Progress, threads
void bindOptics(pybind11::module_ &m);     // snow optics, KZ04 albedos, ice and water absorption
void bindSnow(pybind11::module_ &m);       // Add Snow Layer
void bindTransport(pybind11::module_ &m);  // lights, bake, reference tools
void bindGrains(pybind11::module_ &m);    // grain snow: accumulation, grain renderer, pile albedo
void bindStructure(pybind11::module_ &m); // small-scale structure: sub-balls, glints
void bindIo(pybind11::module_ &m);         // reading grids back
}  // namespace firncore
