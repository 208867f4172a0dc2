// Bindings of the hierarchy coupling (cpp/coupling, cpp/field): exchange grids, interfaces and
// the Level methods that attach coupling forces and the fine level's region outlet. Arrays go
// to numpy; the controllers that use them are in python/grainscale/hierarchy.py.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "coupling/interface.hpp"
#include "coupling/level_coupling.hpp"

namespace py = pybind11;
using namespace grainscale;

namespace {

py::array_t<Real> rows3(const std::vector<Vec3>& v) {
  py::array_t<Real> out({static_cast<py::ssize_t>(v.size()), py::ssize_t(3)});
  auto o = out.mutable_unchecked<2>();
  for (std::size_t k = 0; k < v.size(); ++k)
    for (int c = 0; c < 3; ++c) o(k, c) = v[k][c];
  return out;
}

py::array_t<Real> vector_of(const std::vector<Real>& v) {
  py::array_t<Real> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

std::vector<Vec3> vec3_rows(const py::array_t<Real, py::array::c_style | py::array::forcecast>& a,
                            std::size_t n, const char* what) {
  if (a.ndim() != 2 || a.shape(1) != 3 || static_cast<std::size_t>(a.shape(0)) != n)
    throw py::value_error(std::string(what) + " must have shape (" + std::to_string(n) + ", 3)");
  std::vector<Vec3> out(n);
  auto r = a.unchecked<2>();
  for (std::size_t k = 0; k < n; ++k) out[k] = Vec3(r(k, 0), r(k, 1), r(k, 2));
  return out;
}

std::vector<Real> reals(const py::array_t<Real, py::array::c_style | py::array::forcecast>& a,
                        std::size_t n, const char* what) {
  if (a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n)
    throw py::value_error(std::string(what) + " must have shape (" + std::to_string(n) + ",)");
  return std::vector<Real>(a.data(), a.data() + n);
}

using Array = py::array_t<Real, py::array::c_style | py::array::forcecast>;

py::dict flux_dict(const std::vector<FaceFlux>& f) {
  std::vector<Real> mass(f.size()), count(f.size()), inertia(f.size());
  std::vector<Vec3> momentum(f.size()), spin(f.size());
  for (std::size_t k = 0; k < f.size(); ++k) {
    mass[k] = f[k].mass;
    count[k] = f[k].count;
    inertia[k] = f[k].inertia;
    momentum[k] = f[k].momentum;
    spin[k] = f[k].spin;
  }
  py::dict d;
  d["mass"] = vector_of(mass);
  d["count"] = vector_of(count);
  d["momentum"] = rows3(momentum);
  d["spin"] = rows3(spin);
  d["inertia"] = vector_of(inertia);
  return d;
}

std::vector<FaceFlux> face_fluxes(const py::dict& d, std::size_t n) {
  const auto mass = reals(Array::ensure(d["mass"]), n, "flux mass");
  const auto count = reals(Array::ensure(d["count"]), n, "flux count");
  const auto momentum = vec3_rows(Array::ensure(d["momentum"]), n, "flux momentum");
  const auto spin = vec3_rows(Array::ensure(d["spin"]), n, "flux spin");
  const auto inertia = reals(Array::ensure(d["inertia"]), n, "flux inertia");
  std::vector<FaceFlux> f(n);
  for (std::size_t k = 0; k < n; ++k) {
    f[k].mass = mass[k];
    f[k].count = count[k];
    f[k].momentum = momentum[k];
    f[k].spin = spin[k];
    f[k].inertia = inertia[k];
  }
  return f;
}

py::dict fields_dict(const CellFields& f) {
  py::dict d;
  d["samples"] = f.samples;
  d["mass"] = vector_of(f.mass);
  d["solid_fraction"] = vector_of(f.solid_fraction);
  d["particles"] = vector_of(f.particles);
  d["velocity"] = rows3(f.velocity);
  d["velocity_min"] = rows3(f.velocity_min);
  d["velocity_max"] = rows3(f.velocity_max);
  d["velocity_spread"] = rows3(f.velocity_spread);
  py::array_t<Real> stress(
      {static_cast<py::ssize_t>(f.stress.size()), py::ssize_t(3), py::ssize_t(3)});
  auto s = stress.mutable_unchecked<3>();
  for (std::size_t k = 0; k < f.stress.size(); ++k)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) s(k, r, c) = f.stress[k][3 * r + c];
  d["stress"] = stress;
  return d;
}

}  // namespace

void export_coupling(py::module_& m) {
  py::class_<CellAverager>(m, "CellAverager")
      .def(py::init([](std::array<Real, 3> origin, std::array<Real, 3> edge,
                       std::array<int, 3> dims, int dimension) {
             FieldGrid g;
             g.origin = Vec3(origin[0], origin[1], origin[2]);
             g.edge = Vec3(edge[0], edge[1], edge[2]);
             g.dims = dims;
             for (int a = 0; a < 3; ++a)
               if (!(g.edge[a] > 0) || g.dims[a] < 1)
                 throw py::value_error("CellAverager: cell edges must be positive and counts >= 1");
             return CellAverager(g, dimension);
           }),
           py::arg("origin"), py::arg("edge"), py::arg("dims"), py::arg("dimension"))
      .def(
          "sample",
          [](CellAverager& a, Level& l) { a.sample(l.particles(), l.last_stats(), l.domain()); },
          py::arg("level"))
      .def_property_readonly("samples", &CellAverager::samples)
      .def(
          "finish",
          [](CellAverager& a, Level& l) {
            CellFields f;
            {
              py::gil_scoped_release release;
              f = a.finish(l.comm());
            }
            return fields_dict(f);
          },
          py::arg("level"));

  py::class_<Interface>(m, "Interface")
      .def(py::init([](const Region& region, Real cell_size, Level& parent,
                       const SizeDistribution& fine_radius, Real fine_density, int fine_material,
                       Real size_ratio, Real deadband, std::uint64_t seed) {
             InterfaceSpec s;
             s.region = region;
             s.cell_size = cell_size;
             s.fine_radius = fine_radius;
             s.fine_density = fine_density;
             s.fine_material = fine_material;
             s.size_ratio = size_ratio;
             s.deadband = deadband;
             s.seed = seed;
             return Interface(s, parent.domain(), parent.dimension());
           }),
           py::arg("region"), py::arg("cell_size"), py::arg("parent"), py::arg("fine_radius"),
           py::arg("fine_density"), py::arg("fine_material"), py::arg("size_ratio"),
           py::arg("deadband"), py::arg("seed"))
      .def("grid",
           [](const Interface& it) {
             const ExchangeGrid& g = it.grid();
             const FieldGrid& f = g.grid();
             py::dict d;
             d["origin"] = std::array<Real, 3>{f.origin[0], f.origin[1], f.origin[2]};
             d["edge"] = std::array<Real, 3>{f.edge[0], f.edge[1], f.edge[2]};
             d["dims"] = f.dims;
             std::vector<Real> inside(f.n_cells()), boundary(f.n_cells());
             for (int c = 0; c < f.n_cells(); ++c) {
               inside[c] = g.inside(c);
               boundary[c] = g.boundary(c);
             }
             d["inside"] = vector_of(inside);
             d["boundary"] = vector_of(boundary);
             const auto& faces = g.faces();
             std::vector<Real> cell(faces.size()), axis(faces.size()), area(faces.size());
             std::vector<Vec3> normal(faces.size()), centre(faces.size());
             for (std::size_t k = 0; k < faces.size(); ++k) {
               cell[k] = faces[k].cell;
               axis[k] = faces[k].axis;
               area[k] = faces[k].area;
               normal[k] = faces[k].normal;
               centre[k] = faces[k].centre;
             }
             d["face_cell"] = vector_of(cell);
             d["face_axis"] = vector_of(axis);
             d["face_area"] = vector_of(area);
             d["face_normal"] = rows3(normal);
             d["face_centre"] = rows3(centre);
             return d;
           })
      .def(
          "contains",
          [](const Interface& it, std::array<Real, 3> x) {
            return it.grid().contains(Vec3(x[0], x[1], x[2]));
          },
          py::arg("point"))
      .def("start_flux", &Interface::start_flux, py::arg("parent"), py::arg("margin"),
           py::call_guard<py::gil_scoped_release>())
      .def(
          "finish_flux",
          [](Interface& it, Level& parent) {
            IntervalFlux f;
            {
              py::gil_scoped_release release;
              f = it.finish_flux(parent);
            }
            py::dict d;
            d["inward"] = flux_dict(f.inward);
            d["outward"] = flux_dict(f.outward);
            d["vanished_mass"] = f.vanished_mass;
            d["vanished_count"] = f.vanished_count;
            d["vanished_lost_mass"] = f.vanished_lost_mass;
            d["inside_mass"] = f.inside_mass;
            return d;
          },
          py::arg("parent"))
      .def(
          "book",
          [](Interface& it, const py::dict& flux, const Array& beyond) {
            const std::size_t n = it.inserters().size();
            IntervalFlux f;
            f.inward = face_fluxes(flux["inward"].cast<py::dict>(), n);
            f.outward = face_fluxes(flux["outward"].cast<py::dict>(), n);
            it.book(f, vec3_rows(beyond, n, "beyond velocity"));
          },
          py::arg("flux"), py::arg("beyond"))
      .def(
          "credit",
          [](Interface& it, const Array& left) {
            it.credit(reals(left, it.inserters().size(), "left mass"));
          },
          py::arg("left"))
      .def("extract", &Interface::extract, py::arg("child"),
           py::call_guard<py::gil_scoped_release>())
      .def(
          "remove_shadow",
          [](Interface& it, Level& parent, const Array& excess, std::array<Real, 3> near,
             Real budget) {
            std::vector<Real> e = reals(excess, it.grid().grid().n_cells(), "excess");
            py::gil_scoped_release release;
            return it.remove_shadow(parent, std::move(e), Vec3(near[0], near[1], near[2]), budget);
          },
          py::arg("parent"), py::arg("excess"), py::arg("near"), py::arg("budget"))
      .def(
          "allow_advance",
          [](Interface& it, const Array& mass) {
            auto& ins = it.inserters();
            const auto m = reals(mass, ins.size(), "advance mass");
            for (std::size_t k = 0; k < ins.size(); ++k) ins[k].allow_advance(m[k]);
          },
          py::arg("mass"))
      .def("insert", &Interface::insert, py::arg("child"), py::arg("parent"),
           py::call_guard<py::gil_scoped_release>())
      .def("inserter_status",
           [](const Interface& it) {
             const auto& ins = it.inserters();
             const std::size_t n = ins.size();
             std::vector<Real> fed(n), credited(n), debited(n), inserted(n), extracted(n),
                 pending(n), count(n), advanced(n), outstanding(n);
             for (std::size_t k = 0; k < n; ++k) {
               fed[k] = ins[k].fed_mass();
               credited[k] = ins[k].credited_mass();
               debited[k] = ins[k].debited_mass();
               inserted[k] = ins[k].inserted_mass();
               extracted[k] = ins[k].extracted_mass();
               pending[k] = ins[k].pending_mass();
               count[k] = static_cast<Real>(ins[k].inserted_count());
               advanced[k] = ins[k].advanced_mass();
               outstanding[k] = ins[k].outstanding_advance();
             }
             py::dict d;
             d["fed_mass"] = vector_of(fed);
             d["credited_mass"] = vector_of(credited);
             d["debited_mass"] = vector_of(debited);
             d["inserted_mass"] = vector_of(inserted);
             d["extracted_mass"] = vector_of(extracted);
             d["pending_mass"] = vector_of(pending);
             d["inserted_count"] = vector_of(count);
             d["advanced_mass"] = vector_of(advanced);
             d["outstanding_advance"] = vector_of(outstanding);
             return d;
           })
      .def("inserter_states",
           [](const Interface& it) {
             std::vector<std::string> out;
             for (const FluxInserter& f : it.inserters()) out.push_back(f.save_state());
             return out;
           })
      .def(
          "load_inserter_states",
          [](Interface& it, const std::vector<std::string>& states) {
            if (states.size() != it.inserters().size())
              throw py::value_error("checkpoint holds " + std::to_string(states.size()) +
                                    " interface inserters, this interface has " +
                                    std::to_string(it.inserters().size()));
            for (std::size_t k = 0; k < states.size(); ++k) it.inserters()[k].load_state(states[k]);
          },
          py::arg("states"))
      .def("sample", &Interface::sample, py::arg("level"), py::arg("child"),
           py::call_guard<py::gil_scoped_release>())
      .def(
          "finish_average",
          [](Interface& it, Level& level, bool child) {
            CellFields f;
            {
              py::gil_scoped_release release;
              f = it.finish_average(level, child);
            }
            return fields_dict(f);
          },
          py::arg("level"), py::arg("child"));

  auto level = py::reinterpret_borrow<py::class_<Level>>(m.attr("Level"));
  level.def(
      "add_coupling",
      [](Level& l, const Interface& it, Real layer, Real fade) {
        return add_coupling(l, CouplingForces(it.shared_grid(), layer, fade));
      },
      py::arg("interface"), py::arg("layer"), py::arg("fade"));
  level.def(
      "set_coupling_acceleration",
      [](Level& l, int k, const py::array_t<Real, py::array::c_style | py::array::forcecast>& a) {
        CouplingForces& c = coupling(l, k);
        const std::size_t n = c.grid().grid().n_cells();
        c.acceleration = a.size() == 0 ? std::vector<Vec3>() : vec3_rows(a, n, "acceleration");
      },
      py::arg("index"), py::arg("acceleration"));
  level.def("clear_lost_log", &Level::clear_lost_log);
  level.def(
      "set_coupling_velocity_bounds",
      [](Level& l, int k, const Array& lo, const Array& hi) {
        CouplingForces& c = coupling(l, k);
        const std::size_t n = c.grid().grid().n_cells();
        c.velocity_min = lo.size() == 0 ? std::vector<Vec3>() : vec3_rows(lo, n, "velocity_min");
        c.velocity_max = lo.size() == 0 ? std::vector<Vec3>() : vec3_rows(hi, n, "velocity_max");
      },
      py::arg("index"), py::arg("velocity_min"), py::arg("velocity_max"));
  level.def(
      "set_coupling_pressure",
      [](Level& l, int k, const py::array_t<Real, py::array::c_style | py::array::forcecast>& p,
         const py::array_t<Real, py::array::c_style | py::array::forcecast>& speed) {
        CouplingForces& c = coupling(l, k);
        const std::size_t n = c.grid().faces().size();
        c.pressure = p.size() == 0 ? std::vector<Real>() : reals(p, n, "pressure");
        c.max_inward_speed = p.size() == 0 ? std::vector<Real>() : reals(speed, n, "speed");
      },
      py::arg("index"), py::arg("pressure"), py::arg("max_inward_speed"));
  level.def(
      "coupling_push_moment",
      [](Level& l, int k) {
        std::vector<Real> m;
        {
          py::gil_scoped_release release;
          m = coupling_push_moment(l, k);
        }
        return py::array_t<Real>(static_cast<py::ssize_t>(m.size()), m.data());
      },
      py::arg("index"));
  level.def(
      "add_region_outlet",
      [](Level& l, const Interface& it, int every, Real band) {
        OutletSpec s;
        s.keep_faces = it.grid().faces().size();
        s.every = every;
        return l.add_region_outlet(s, it.shared_grid(), band);
      },
      py::arg("interface"), py::arg("every"), py::arg("band"));
}
