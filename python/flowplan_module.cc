// flowplan._flowplan: flowplan's C++ library for the Python package
// (python/flowplan/__init__.py). Importing it loads flowplan's native kernels
// (libflowplan_kernels registers its operators with the LibTorch that
// PyTorch runs on), so TorchScript modules that call them load in Python.

#include <pybind11/pybind11.h>

#include <sstream>
#include <string>

#include "core/error.h"
#include "experiment/trained_planner.h"
#include "planning/learned_planner.h"

namespace py = pybind11;

namespace {

/// An exported planner file with flowplan's native kernels, as the bytes of a
/// TorchScript module (torch.jit.load reads them).
py::bytes NativePlanner(const std::string& path) {
  std::string bytes;
  {
    py::gil_scoped_release unlocked;
    const auto file = flowplan::planning::LearnedPlanner::Load(path);
    const auto planner = flowplan::experiment::AssembleNative(*file);
    std::ostringstream out;
    planner->module().save(out);
    bytes = out.str();
  }
  return py::bytes(bytes);
}

}  // namespace

PYBIND11_MODULE(_flowplan, m) {
  m.doc() = "flowplan's C++ library for the Python package `flowplan` (use the package, not this module).";
  static py::exception<flowplan::Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const flowplan::Error& e) {
      error(e.what());
    }
  });
  m.def("native_planner", &NativePlanner, py::arg("path"),
        "The exported planner file at `path` assembled again with flowplan's native kernels: the bytes of its "
        "TorchScript module. Raises flowplan.Error naming the file if it is not a flowplan planner or cannot be "
        "assembled again.");
}
