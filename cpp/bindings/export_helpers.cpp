#include <pybind11/pybind11.h>

#include <memory>
#include <set>
#include <string>

#include "integrate/time_step.hpp"
#include "parallel/communicator.hpp"
#include "parallel/watchdog.hpp"

namespace py = pybind11;
using namespace grainscale;

namespace {

// A wait of the Python package for other ranks (grainscale.parallel.waiting), watched like the
// core's own. Labels are kept for the life of the process: the watching thread may read one
// after its scope ended.
class PythonWait {
 public:
  explicit PythonWait(const std::string& what) {
    static std::set<std::string> labels;
    what_ = labels.insert(what).first->c_str();
  }
  void enter() {
    watchdog::start();
    scope_ = std::make_unique<watchdog::WaitScope>(what_);
  }
  void exit() { scope_.reset(); }

 private:
  const char* what_;
  std::unique_ptr<watchdog::WaitScope> scope_;
};

void export_watchdog(py::module_& m) {
  m.def("set_mpi_timeout", &watchdog::set_timeout, py::arg("seconds"));
  m.def("mpi_timeout", &watchdog::timeout);
  py::class_<PythonWait>(m, "MpiWait")
      .def(py::init<const std::string&>(), py::arg("what"))
      .def("__enter__", [](PythonWait& w) { w.enter(); })
      .def("__exit__", [](PythonWait& w, py::args) { w.exit(); });
}

}  // namespace

void export_helpers(py::module_& m) {
  m.def("rayleigh_time", &rayleigh_time, py::arg("radius"), py::arg("density"),
        py::arg("youngs_modulus"), py::arg("poisson_ratio"));
  m.def("hertz_contact_time", &hertz_contact_time, py::arg("effective_radius"),
        py::arg("effective_mass"), py::arg("effective_youngs"), py::arg("impact_velocity"));
  m.attr("max_rayleigh_fraction") = kMaxRayleighFraction;
  m.def("with_mpi", &Communicator::mpi_available, "Whether the core was built with MPI.");
  export_watchdog(m);
}
