#include <pybind11/pybind11.h>

#include "integrate/time_step.hpp"
#include "parallel/communicator.hpp"

namespace py = pybind11;
using namespace grainscale;

void export_helpers(py::module_& m) {
  m.def("rayleigh_time", &rayleigh_time, py::arg("radius"), py::arg("density"),
        py::arg("youngs_modulus"), py::arg("poisson_ratio"));
  m.def("hertz_contact_time", &hertz_contact_time, py::arg("effective_radius"),
        py::arg("effective_mass"), py::arg("effective_youngs"), py::arg("impact_velocity"));
  m.attr("max_rayleigh_fraction") = kMaxRayleighFraction;
  m.def("with_mpi", &Communicator::mpi_available, "Whether the core was built with MPI.");
}
