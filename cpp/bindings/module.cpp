// grainscale._core: the only translation units that include pybind11. C++ exceptions map to
// Python: InvalidArgument (std::invalid_argument) -> ValueError, others -> RuntimeError.
#include <pybind11/pybind11.h>

namespace py = pybind11;

void export_level(py::module_& m);
void export_helpers(py::module_& m);
void export_checkpoint(py::module_& m);
void export_insert(py::module_& m);    // after export_level: adds methods to Level
void export_coupling(py::module_& m);  // after export_insert: adds methods to Level

PYBIND11_MODULE(_core, m) {
  m.doc() = "grainscale C++ core (private; use the grainscale package)";
  export_level(m);
  export_helpers(m);
  export_checkpoint(m);
  export_insert(m);
  export_coupling(m);
}
