// Errors, progress and threads: what every other binding builds on.
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "firn/util/error.h"
#include "firn/util/progress.h"
#include "firn/util/threads.h"

namespace py = pybind11;

namespace firncore {

namespace {

void bindErrors(py::module_ &m) {
    // Raised by long calls when their Progress was cancelled.
    py::register_exception<firn::Cancelled>(m, "Cancelled");
    // A request over a resource limit (e.g. too many voxels): the message says what to change.
    py::register_exception<firn::BudgetExceeded>(m, "BudgetError", PyExc_ValueError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const firn::IoError &e) {
            PyErr_SetString(PyExc_OSError, e.what());
        }
    });
    // Registered after the IoError translator, so tried before it: a call that reads one file and writes another
    // (the bake) says which of the two failed. Both are OSError.
    py::register_exception<firn::ReadError>(m, "ReadError", PyExc_OSError);
    py::register_exception<firn::WriteError>(m, "WriteError", PyExc_OSError);
}

void bindProgress(py::module_ &m) {
    py::class_<firn::Progress, std::shared_ptr<firn::Progress>>(m, "Progress", R"doc(
Progress of a long core call, shared with the caller. Poll `fraction` and `stage` from any thread
(a Blender modal timer does), call `cancel()` to stop the work: the call then raises firncore.Cancelled.
An optional callback(fraction, stage) is called from the working thread with the GIL held, at most ten
times a second but on every new stage.)doc")
        .def(py::init([](std::optional<py::function> callback) {
                 if (!callback) return std::make_shared<firn::Progress>();
                 // The worker runs without the GIL; take it for the Python callback only.
                 auto shared = std::make_shared<py::function>(std::move(*callback));
                 return std::make_shared<firn::Progress>([shared](double fraction, const std::string &stage) {
                     py::gil_scoped_acquire gil;
                     (*shared)(fraction, stage);
                 });
             }),
             py::arg("callback") = py::none())
        .def_property_readonly("fraction", &firn::Progress::fraction, "Done so far, 0..1.")
        .def_property_readonly("stage", &firn::Progress::stage, "What the work is doing now.")
        .def_property_readonly("cancelled", &firn::Progress::isCancelled)
        .def("cancel", &firn::Progress::cancel, "Ask the work to stop as soon as it can.");
}

}  // namespace

void bindUtil(py::module_ &m) {
    bindErrors(m);
    bindProgress(m);
    m.def("set_thread_count", &firn::setThreadCount, py::arg("count"),
          "Caps the threads the core's parallel loops use; 0 means all hardware threads.");
    m.def("hardware_threads", &firn::hardwareThreadCount, "Threads the core uses when uncapped.");
}

}  // namespace firncore
