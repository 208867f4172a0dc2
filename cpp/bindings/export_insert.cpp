// Bindings of the insertion module: size distributions, regions, faces, and the Level methods for
// packing, streams, outlets and particle deletion (added to the Level class of export_level.cpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <limits>
#include <optional>

#include "bindings/mesh_arrays.hpp"
#include "level/level.hpp"

namespace py = pybind11;
using namespace grainscale;

namespace {

using V3 = std::array<Real, 3>;
Vec3 vec(const V3& a) { return Vec3(a[0], a[1], a[2]); }

template <class T>
py::array_t<T> to_numpy(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

StreamInserter& stream_at(Level& l, int k) {
  if (k < 0 || k >= static_cast<int>(l.streams().size()))
    throw py::index_error("no stream with index " + std::to_string(k));
  return l.streams()[k];
}

Outlet& outlet_at(Level& l, int k) {
  if (k < 0 || k >= static_cast<int>(l.outlets().size()))
    throw py::index_error("no outlet with index " + std::to_string(k));
  return l.outlets()[k];
}

}  // namespace

void export_insert(py::module_& m) {
  py::class_<SizeDistribution>(m, "SizeDistribution")
      .def_static("monodisperse", &SizeDistribution::monodisperse, py::arg("radius"))
      .def_static("uniform", &SizeDistribution::uniform, py::arg("min"), py::arg("max"))
      .def_static("normal", &SizeDistribution::normal, py::arg("mean"), py::arg("std"),
                  py::arg("min"), py::arg("max"))
      .def_static("lognormal", &SizeDistribution::lognormal, py::arg("median"), py::arg("sigma"),
                  py::arg("min"), py::arg("max"))
      .def_static("discrete", &SizeDistribution::discrete, py::arg("radii"), py::arg("weights"),
                  py::arg("by_mass"))
      .def_property_readonly("name", &SizeDistribution::name)
      .def_property_readonly("min_radius", &SizeDistribution::min_radius)
      .def_property_readonly("max_radius", &SizeDistribution::max_radius)
      .def(
          "sample",
          [](const SizeDistribution& d, py::ssize_t n, std::uint64_t seed) {
            if (n < 0)
              throw py::value_error("sample.n must be non-negative, got " + std::to_string(n));
            py::array_t<Real> out(n);
            Real* o = out.mutable_data();
            {
              py::gil_scoped_release release;
              Rng rng(seed);
              for (py::ssize_t k = 0; k < n; ++k) o[k] = d.sample(rng);
            }
            return out;
          },
          py::arg("n"), py::arg("seed"));

  py::class_<Region>(m, "Region")
      .def_static(
          "box", [](V3 lo, V3 hi) { return Region::box(vec(lo), vec(hi)); }, py::arg("lo"),
          py::arg("hi"))
      .def_static(
          "cylinder",
          [](V3 c, V3 axis, Real radius, Real height) {
            return Region::cylinder(vec(c), vec(axis), radius, height);
          },
          py::arg("centre"), py::arg("axis"), py::arg("radius"), py::arg("height"))
      .def_static(
          "mesh",
          [](const VertexArray& vertices, const TriangleArray& triangles, const std::string& what) {
            const TriangleMesh m = mesh_from_arrays(vertices, triangles);
            return Region::mesh(m.vertices, m.triangles, what);
          },
          py::arg("vertices"), py::arg("triangles"), py::arg("what") = "Mesh region")
      .def_property_readonly("volume", &Region::volume)
      .def("bounds",
           [](const Region& r) {
             Vec3 lo, hi;
             r.bounds(lo, hi);
             return std::make_pair(V3{lo[0], lo[1], lo[2]}, V3{hi[0], hi[1], hi[2]});
           })
      .def(
          "contains",
          [](const Region& r,
             const py::array_t<Real, py::array::c_style | py::array::forcecast>& points,
             Real radius) {
            if (points.ndim() != 2 || points.shape(1) != 3)
              throw py::value_error("Region.contains.points must have shape (N, 3)");
            const py::ssize_t n = points.shape(0);
            py::array_t<bool> out(n);
            const Real* p = points.data();
            bool* o = out.mutable_data();
            for (py::ssize_t k = 0; k < n; ++k)
              o[k] = r.contains(Vec3(p[3 * k], p[3 * k + 1], p[3 * k + 2]), radius);
            return out;
          },
          py::arg("points"), py::arg("radius") = 0.0);

  py::class_<Face>(m, "Face")
      .def_static(
          "rectangle", [](V3 c, V3 e1, V3 e2) { return Face::rectangle(vec(c), vec(e1), vec(e2)); },
          py::arg("corner"), py::arg("edge1"), py::arg("edge2"))
      .def_static(
          "disc", [](V3 c, V3 n, Real r) { return Face::disc(vec(c), vec(n), r); },
          py::arg("centre"), py::arg("normal"), py::arg("radius"))
      .def_property_readonly("area", &Face::area)
      .def_property_readonly(
          "normal", [](const Face& f) { return V3{f.normal()[0], f.normal()[1], f.normal()[2]}; });

  auto level = py::reinterpret_borrow<py::class_<Level>>(m.attr("Level"));
  level
      .def(
          "pack",
          [](Level& l, const Region& region, const SizeDistribution& radius, std::int64_t count,
             Real volume_fraction, std::int32_t material, V3 velocity, std::uint64_t seed,
             int max_attempts) {
            PackSpec s;
            s.region = region;
            s.radius = radius;
            s.count = count;
            s.volume_fraction = volume_fraction;
            s.material = material;
            s.velocity = vec(velocity);
            s.seed = seed;
            s.max_attempts = max_attempts;
            return l.pack(s);
          },
          py::arg("region"), py::arg("radius"), py::arg("count"), py::arg("volume_fraction"),
          py::arg("material"), py::arg("velocity"), py::arg("seed"), py::arg("max_attempts"))
      .def(
          "add_stream",
          [](Level& l, const Face& face, const SizeDistribution& radius, Real mass_rate,
             std::int32_t material, V3 velocity, std::uint64_t seed, Real start,
             std::optional<Real> stop, std::optional<Real> every, int max_attempts) {
            StreamSpec s;
            s.face = face;
            s.radius = radius;
            s.mass_rate = mass_rate;
            s.material = material;
            s.velocity = vec(velocity);
            s.seed = seed;
            s.start = start;
            s.stop = stop ? *stop : std::numeric_limits<Real>::infinity();
            s.every = every ? *every : 0;
            if (every && !(*every > 0)) throw_invalid("Stream.every", "positive (s)", *every);
            s.max_attempts = max_attempts;
            return l.add_stream(s);
          },
          py::arg("face"), py::arg("radius"), py::arg("mass_rate"), py::arg("material"),
          py::arg("velocity"), py::arg("seed"), py::arg("start"), py::arg("stop"), py::arg("every"),
          py::arg("max_attempts"))
      .def("num_streams", [](Level& l) { return l.streams().size(); })
      .def(
          "stream_status",
          [](Level& l, int k) {
            const StreamInserter& s = stream_at(l, k);
            py::dict d;
            d["requested_mass"] = s.requested_mass(l.time());
            d["scheduled_mass"] = s.scheduled_mass();
            d["inserted_mass"] = s.inserted_mass();
            d["pending_mass"] = s.pending_mass();
            d["inserted_count"] = s.inserted_count();
            d["pending_count"] = s.pending_count();
            d["batches"] = s.batches();
            d["interval"] = s.interval();
            d["thickness"] = s.thickness();
            const Vec3& n = s.direction();
            d["direction"] = V3{n[0], n[1], n[2]};
            return d;
          },
          py::arg("index"))
      .def(
          "stream_slab", [](Level& l, int k) { return stream_at(l, k).slab(); }, py::arg("index"))
      .def(
          "stream_get_state", [](Level& l, int k) { return stream_at(l, k).save_state(); },
          py::arg("index"))
      .def(
          "stream_set_state",
          [](Level& l, int k, const std::string& s) { stream_at(l, k).load_state(s); },
          py::arg("index"), py::arg("state"))
      .def(
          "add_outlet",
          [](Level& l, const Region& region, int every) {
            OutletSpec s;
            s.region = region;
            s.every = every;
            return l.add_outlet(s);
          },
          py::arg("region"), py::arg("every"))
      .def("num_outlets", [](Level& l) { return l.outlets().size(); })
      .def(
          "outlet_status",
          [](Level& l, int k) {
            const Outlet& o = outlet_at(l, k);
            py::dict d;
            d["removed_count"] = o.removed_count();
            d["removed_mass"] = o.removed_mass();
            const Vec3& m = o.removed_moment();
            d["removed_moment"] = py::make_tuple(m[0], m[1], m[2]);
            d["removed_face_mass"] = to_numpy(o.removed_face_mass());
            return d;
          },
          py::arg("index"))
      .def(
          "outlet_history",
          [](Level& l, int k) {
            const Outlet& o = outlet_at(l, k);
            return py::make_tuple(to_numpy(o.history_time()), to_numpy(o.history_mass()),
                                  to_numpy(o.history_count()));
          },
          py::arg("index"))
      .def(
          "outlet_get_state", [](Level& l, int k) { return outlet_at(l, k).save_state(); },
          py::arg("index"))
      .def(
          "outlet_set_state",
          [](Level& l, int k, const std::string& s) { outlet_at(l, k).load_state(s); },
          py::arg("index"), py::arg("state"))
      .def(
          "remove_particles",
          [](Level& l, const std::vector<GlobalId>& ids) { return l.remove_particles(ids); },
          py::arg("ids"))
      .def("smallest_insertion_rayleigh_time", &Level::smallest_insertion_rayleigh_time);
}
