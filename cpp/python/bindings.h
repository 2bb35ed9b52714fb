#pragma once

// One binding function per core folder (cpp/firn/<folder>/ -> bind_<folder>.cpp); firncore.cpp calls them
// in layer order.
#include <string>
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

// A settings object (a bound class) from keyword arguments, each an attribute of it: Settings(depth=0.2, seed=3).
// An unknown name is a TypeError.
template <class Settings>
Settings settingsFromKwargs(const pybind11::kwargs &kwargs, const char *typeName) {
    pybind11::object self = pybind11::cast(Settings{});
    for (const auto &item : kwargs) {
        const auto key = item.first.cast<std::string>();
        if (!pybind11::hasattr(self, key.c_str()))
            throw pybind11::type_error(std::string(typeName) + " has no '" + key + "'");
        pybind11::setattr(self, key.c_str(), item.second);
    }
    return self.cast<Settings>();
}

void bindUtil(pybind11::module_ &m);       // errors, Progress, threads
void bindOptics(pybind11::module_ &m);     // snow optics, KZ04 albedos, ice and water absorption
void bindSnow(pybind11::module_ &m);       // Add Snow Layer
void bindTransport(pybind11::module_ &m);  // lights, bake, reference tools
void bindGrains(pybind11::module_ &m);     // grain snow: accumulation, grain renderer, pile albedo
void bindSpray(pybind11::module_ &m);      // snow thrown by moving objects, their tracks
void bindStructure(pybind11::module_ &m);  // small-scale structure: sub-balls, glints
void bindIo(pybind11::module_ &m);         // reading grids back
}  // namespace firncore
