// Checkpoint state of a Level as a flat dict of numpy arrays ("reals/<key>", "ints/<key>",
// "texts/<key>"), written to HDF5 by grainscale.io.checkpoint.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "level/level.hpp"

namespace py = pybind11;
using namespace grainscale;

void export_checkpoint(py::module_& m) {
  auto level = py::reinterpret_borrow<py::class_<Level>>(m.attr("Level"));
  level.def("save_state", [](Level& l) {
    const LevelState s = l.save_state();
    py::dict out;
    for (const auto& [key, v] : s.reals)
      out[py::str("reals/" + key)] = py::array_t<double>(v.size(), v.data());
    for (const auto& [key, v] : s.ints)
      out[py::str("ints/" + key)] = py::array_t<std::int64_t>(v.size(), v.data());
    for (const auto& [key, v] : s.texts) out[py::str("texts/" + key)] = py::str(v);
    return out;
  });
  auto to_state = [](const py::dict& d) {
    LevelState s;
    for (const auto& [k, v] : d) {
      const std::string key = py::cast<std::string>(k);
      if (key.rfind("reals/", 0) == 0) {
        auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
        if (!a) throw py::value_error("checkpoint entry '" + key + "' is not numeric");
        s.reals[key.substr(6)].assign(a.data(), a.data() + a.size());
      } else if (key.rfind("ints/", 0) == 0) {
        auto a = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(v);
        if (!a) throw py::value_error("checkpoint entry '" + key + "' is not integer");
        s.ints[key.substr(5)].assign(a.data(), a.data() + a.size());
      } else if (key.rfind("texts/", 0) == 0) {
        s.texts[key.substr(6)] = py::cast<std::string>(v);
      }
    }
    return s;
  };
  level.def(
      "load_state", [to_state](Level& l, const py::dict& d) { l.load_state(to_state(d)); },
      py::arg("state"));
  level.def(
      "load_redistributed",
      [to_state](Level& l, const py::list& parts) {
        std::vector<LevelState> states;
        for (const auto& d : parts) states.push_back(to_state(py::cast<py::dict>(d)));
        l.load_redistributed(states);
      },
      py::arg("states"));
  level.def(
      "check_state",
      [to_state](const Level& l, const py::dict& d, bool exact, int n_materials) {
        l.check_state(to_state(d), exact, n_materials);
      },
      py::arg("state"), py::arg("exact"), py::arg("n_materials"));
  level.def("signature", &Level::signature);
}
