#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/simd_pack.hpp"
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

#ifndef GRAINSCALE_NATIVE_BUILD
#define GRAINSCALE_NATIVE_BUILD 0
#endif
#ifndef GRAINSCALE_ARCH
#define GRAINSCALE_ARCH "unknown"
#endif
#ifndef GRAINSCALE_BUILD_TYPE
#define GRAINSCALE_BUILD_TYPE "unknown"
#endif

// The vector instruction sets the compiler was allowed to use (its predefined macros under the
// core's -march flags): what the compiled code needs from the CPU.
std::vector<std::string> instruction_sets() {
  std::vector<std::string> isa;
#ifdef __SSE4_2__
  isa.emplace_back("sse4.2");
#endif
#ifdef __AVX__
  isa.emplace_back("avx");
#endif
#ifdef __AVX2__
  isa.emplace_back("avx2");
#endif
#ifdef __FMA__
  isa.emplace_back("fma");
#endif
#ifdef __AVX512F__
  isa.emplace_back("avx512f");
#endif
#ifdef __ARM_NEON
  isa.emplace_back("neon");
#endif
  return isa;
}

std::string compiler() {
#if defined(__clang__)
  return std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  return std::string("gcc ") + __VERSION__;
#else
  return "unknown";
#endif
}

py::dict build_info() {
  const bool native = GRAINSCALE_NATIVE_BUILD != 0;
  const std::string arch = GRAINSCALE_ARCH;
  py::dict info;
  info["native"] = native;
  info["arch"] = arch;
  info["kind"] = native ? std::string("native") : "portable (" + arch + ")";
  info["instruction_sets"] = instruction_sets();
  // Contacts the pair loop evaluates at once (core/simd_pack.hpp; 1 with GRAINSCALE_SIMD=OFF).
  info["simd_lanes"] = kPackLanes;
  info["mpi"] = Communicator::mpi_available();
  info["build_type"] = std::string(GRAINSCALE_BUILD_TYPE);
  info["compiler"] = compiler();
  // Instrumented code runs several times slower: timing checks do not apply.
  info["sanitized"] = GRAINSCALE_SANITIZED_BUILD != 0;
  return info;
}

}  // namespace

void export_helpers(py::module_& m) {
  m.def("rayleigh_time", &rayleigh_time, py::arg("radius"), py::arg("density"),
        py::arg("youngs_modulus"), py::arg("poisson_ratio"));
  m.def("hertz_contact_time", &hertz_contact_time, py::arg("effective_radius"),
        py::arg("effective_mass"), py::arg("effective_youngs"), py::arg("impact_velocity"));
  m.attr("max_rayleigh_fraction") = kMaxRayleighFraction;
  m.def("with_mpi", &Communicator::mpi_available, "Whether the core was built with MPI.");
  m.def("build_info", &build_info,
        "How the core was built: native (-march=native) or portable, the instruction sets the "
        "compiled code uses, MPI, build type, compiler, sanitizers.");
  export_watchdog(m);
}
