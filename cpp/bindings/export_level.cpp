#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <optional>

#include "bindings/mesh_arrays.hpp"
#include "level/level.hpp"

namespace py = pybind11;
using namespace grainscale;

namespace {

using Array3 = py::array_t<Real, py::array::c_style | py::array::forcecast>;

using Vec3A = std::array<Real, 3>;
Vec3 to_vec3(const Vec3A& a) { return Vec3(a[0], a[1], a[2]); }
std::array<Real, 3> from_vec3(const Vec3& v) { return {v[0], v[1], v[2]}; }

// Zero-copy view of the first n entries of a SharedArray. The capsule holds a reference to the
// buffer, so the view stays memory-safe even if the store later grows into a new buffer.
template <class T, class Elem>
py::array view(SharedArray<T>& a, Index n, std::vector<py::ssize_t> shape) {
  if (a.data() == nullptr) a.reserve(1);  // numpy wants a real pointer even for empty views
  auto* keep = new std::shared_ptr<T[]>(a.buffer());
  py::capsule owner(keep, [](void* p) { delete static_cast<std::shared_ptr<T[]>*>(p); });
  std::vector<py::ssize_t> strides;
  if (shape.size() == 2)
    strides = {static_cast<py::ssize_t>(sizeof(T)), sizeof(Elem)};
  else
    strides = {static_cast<py::ssize_t>(sizeof(T))};
  shape[0] = n;
  return py::array(py::dtype::of<Elem>(), shape, strides, reinterpret_cast<Elem*>(a.data()), owner);
}

const Real* optional_rows(const py::object& o, Index n, const char* name, Array3& keep) {
  if (o.is_none()) return nullptr;
  keep = Array3::ensure(o);
  if (!keep || keep.ndim() != 2 || keep.shape(0) != n || keep.shape(1) != 3)
    throw py::value_error(std::string("add_particles.") + name + " must have shape (N, 3)");
  return keep.data();
}

}  // namespace

void export_level(py::module_& m) {
  py::class_<Interaction>(m, "Interaction")
      .def(py::init<>())
      .def_readwrite("restitution", &Interaction::restitution)
      .def_readwrite("friction", &Interaction::friction)
      .def_readwrite("rolling_friction", &Interaction::rolling_friction)
      .def_readwrite("rolling_damping", &Interaction::rolling_damping)
      .def_readwrite("normal_stiffness", &Interaction::normal_stiffness)
      .def_readwrite("tangential_stiffness", &Interaction::tangential_stiffness)
      .def_readwrite("characteristic_velocity", &Interaction::characteristic_velocity)
      .def_readwrite("eepa_exponent", &Interaction::eepa_exponent)
      .def_readwrite("loading_stiffness", &Interaction::loading_stiffness)
      .def_readwrite("unloading_ratio", &Interaction::unloading_ratio)
      .def_readwrite("adhesive_stiffness", &Interaction::adhesive_stiffness)
      .def_readwrite("pull_off_force", &Interaction::pull_off_force)
      .def_readwrite("adhesion_exponent", &Interaction::adhesion_exponent);
  m.def("supported_contact_laws", &supported_contact_laws);

  py::class_<Level>(m, "Level")
      .def(py::init([](std::array<Real, 3> lo, std::array<Real, 3> hi, std::array<bool, 3> periodic,
                       std::optional<std::int64_t> comm) {
             const Domain domain(to_vec3(lo), to_vec3(hi), periodic);
             return Level(domain, comm ? Communicator::from_fortran_handle(*comm) : Communicator());
           }),
           py::arg("lo"), py::arg("hi"), py::arg("periodic"), py::arg("comm") = py::none())
      .def_property_readonly("rank", [](Level& l) { return l.comm().rank(); })
      .def_property_readonly("ranks", [](Level& l) { return l.comm().size(); })
      .def("set_processor_grid", &Level::set_processor_grid, py::arg("grid"))
      .def("decomposition",
           [](Level& l) {
             const Decomposition& d = l.decomposition();
             py::dict out;
             out["grid"] = d.grid;
             out["coords"] = d.coords;
             out["cuts"] = d.cuts;
             return out;
           })
      .def("balance", &Level::balance, py::call_guard<py::gil_scoped_release>())
      .def("set_auto_balance", &Level::set_auto_balance, py::arg("every"), py::arg("threshold"))
      .def("rank_counts", &Level::rank_counts, py::call_guard<py::gil_scoped_release>())
      .def("global_count", &Level::global_count, py::call_guard<py::gil_scoped_release>())
      .def(
          "add_material",
          [](Level& l, Real density, Real E, Real nu) { return l.add_material({density, E, nu}); },
          py::arg("density"), py::arg("youngs_modulus"), py::arg("poisson_ratio"))
      .def(
          "set_contact_law",
          [](Level& l, const std::string& normal, const std::string& rolling, bool limit_force,
             bool tangential_damping, bool incremental, bool project_springs) {
            ContactSettings s;
            s.limit_force = limit_force;
            s.tangential_damping = tangential_damping;
            s.history = incremental ? TangentialHistory::Incremental : TangentialHistory::Total;
            s.spring_rotation = project_springs ? SpringRotation::Project : SpringRotation::Rescale;
            l.set_contact_law(make_contact_law(normal, rolling, s));
          },
          py::arg("normal"), py::arg("rolling"), py::arg("limit_force"),
          py::arg("tangential_damping"), py::arg("incremental"), py::arg("project_springs") = false)
      .def("contact_law_name", [](Level& l) { return law_name(l.contact_law()); })
      .def("set_interaction", &Level::set_interaction, py::arg("i"), py::arg("j"),
           py::arg("interaction"))
      .def("set_default_interaction", &Level::set_default_interaction, py::arg("interaction"))
      .def(
          "set_gravity", [](Level& l, std::array<Real, 3> g) { l.set_gravity(to_vec3(g)); },
          py::arg("gravity"))
      .def("set_time_step", &Level::set_time_step, py::arg("time_step"), py::arg("force"))
      .def("set_skin", &Level::set_skin, py::arg("skin"))
      .def("set_dimension", &Level::set_dimension, py::arg("dimension"))
      .def_property_readonly("dimension", &Level::dimension)
      .def_property_readonly("plane_z", &Level::plane_z)
      .def(
          "add_particles",
          [](Level& l, const Array3& position, const py::object& velocity,
             const py::object& angular_velocity,
             const py::array_t<Real, py::array::c_style | py::array::forcecast>& radius,
             const py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>& material) {
            if (position.ndim() != 2 || position.shape(1) != 3)
              throw py::value_error("add_particles.position must have shape (N, 3)");
            const Index n = static_cast<Index>(position.shape(0));
            if (radius.ndim() != 1 || radius.shape(0) != n)
              throw py::value_error("add_particles.radius must have shape (N,)");
            if (material.ndim() != 1 || material.shape(0) != n)
              throw py::value_error("add_particles.material must have shape (N,)");
            Array3 kv, kw;
            const Real* v = optional_rows(velocity, n, "velocity", kv);
            const Real* w = optional_rows(angular_velocity, n, "angular_velocity", kw);
            return l.add_particles(n, position.data(), v, w, radius.data(), material.data());
          },
          py::arg("position"), py::arg("velocity"), py::arg("angular_velocity"), py::arg("radius"),
          py::arg("material"))
      .def(
          "add_plane_wall",
          [](Level& l, Vec3A point, Vec3A normal, Vec3A velocity, int material) {
            Wall w;
            w.shape = WallShape::Plane;
            w.point = w.origin = to_vec3(point);
            w.normal = to_vec3(normal);
            w.velocity = to_vec3(velocity);
            w.material = material;
            return l.add_wall(w);
          },
          py::arg("point"), py::arg("normal"), py::arg("velocity"), py::arg("material"))
      .def(
          "add_rectangle_wall",
          [](Level& l, Vec3A corner, Vec3A edge1, Vec3A edge2, Vec3A velocity, int material) {
            Wall w;
            w.shape = WallShape::Rectangle;
            w.point = w.origin = to_vec3(corner);
            w.edge1 = to_vec3(edge1);
            w.edge2 = to_vec3(edge2);
            w.velocity = to_vec3(velocity);
            w.material = material;
            return l.add_wall(w);
          },
          py::arg("corner"), py::arg("edge1"), py::arg("edge2"), py::arg("velocity"),
          py::arg("material"))
      .def(
          "add_cylinder_wall",
          [](Level& l, Vec3A point, Vec3A axis, Real radius, Real length, bool inside,
             Vec3A velocity, int material) {
            Wall w;
            w.shape = WallShape::Cylinder;
            w.point = w.origin = to_vec3(point);
            w.axis = to_vec3(axis);
            w.radius = radius;
            w.length = length;
            w.inside = inside;
            w.velocity = to_vec3(velocity);
            w.material = material;
            return l.add_wall(w);
          },
          py::arg("point"), py::arg("axis"), py::arg("radius"), py::arg("length"),
          py::arg("inside"), py::arg("velocity"), py::arg("material"))
      .def(
          "add_mesh_wall",
          [](Level& l, const VertexArray& vertices, const TriangleArray& triangles, Vec3A origin,
             Vec3A velocity, int material) {
            auto mesh = std::make_shared<TriangleMesh>(mesh_from_arrays(vertices, triangles));
            Wall w;
            w.shape = WallShape::Mesh;
            w.mesh = mesh;
            w.point = w.origin = to_vec3(origin);
            w.velocity = to_vec3(velocity);
            w.material = material;
            return l.add_wall(w);
          },
          py::arg("vertices"), py::arg("triangles"), py::arg("origin"), py::arg("velocity"),
          py::arg("material"))
      .def(
          "set_wall_motion",
          [](Level& l, int i, Vec3A velocity, Vec3A angular_velocity, Vec3A origin) {
            l.set_wall_motion(i, to_vec3(velocity), to_vec3(angular_velocity), to_vec3(origin));
          },
          py::arg("index"), py::arg("velocity"), py::arg("angular_velocity"), py::arg("origin"))
      .def(
          "set_wall_servo",
          [](Level& l, int i, bool enabled, Vec3A direction, Real target_force, Real gain,
             Real max_speed, Real integral_gain) {
            Servo s;
            s.enabled = enabled;
            s.direction = to_vec3(direction);
            s.target_force = target_force;
            s.gain = gain;
            s.max_speed = max_speed;
            s.integral_gain = integral_gain;
            l.set_wall_servo(i, s);
          },
          py::arg("index"), py::arg("enabled"), py::arg("direction"), py::arg("target_force"),
          py::arg("gain"), py::arg("max_speed"), py::arg("integral_gain") = 0.0)
      .def(
          "wall_servo_integral", [](Level& l, int i) { return l.walls().at(i).servo.integral; },
          py::arg("index"))
      .def(
          "wall_velocity", [](Level& l, int i) { return from_vec3(l.walls().at(i).velocity); },
          py::arg("index"))
      .def(
          "wall_origin", [](Level& l, int i) { return from_vec3(l.walls().at(i).origin); },
          py::arg("index"))
      .def(
          "wall_vertices",
          [](Level& l, int i) {
            const Wall& w = l.walls().at(i);
            if (!w.mesh) throw py::value_error("wall " + std::to_string(i) + " is not a mesh");
            py::array_t<Real> out(
                {static_cast<py::ssize_t>(w.mesh->vertices.size()), py::ssize_t(3)});
            auto o = out.mutable_unchecked<2>();
            for (std::size_t k = 0; k < w.mesh->vertices.size(); ++k)
              for (int c = 0; c < 3; ++c) o(k, c) = w.mesh->vertices[k][c];
            return out;
          },
          py::arg("index"))
      .def("num_walls", [](Level& l) { return l.walls().size(); })
      .def(
          "wall_force", [](Level& l, int i) { return from_vec3(l.walls().at(i).force); },
          py::arg("index"))
      .def(
          "wall_torque", [](Level& l, int i) { return from_vec3(l.walls().at(i).torque); },
          py::arg("index"))
      .def(
          "wall_point", [](Level& l, int i) { return from_vec3(l.walls().at(i).point); },
          py::arg("index"))
      .def(
          "wall_frame",
          [](Level& l, int i) {
            // The current placement of a plane, rectangle or cylinder (for output).
            const Wall& w = l.walls().at(i);
            py::dict frame;
            frame["point"] = from_vec3(w.point);
            frame["normal"] = from_vec3(w.normal);
            frame["edge1"] = from_vec3(w.edge1);
            frame["edge2"] = from_vec3(w.edge2);
            frame["axis"] = from_vec3(w.axis);
            frame["moving"] = w.servo.enabled || w.velocity.squaredNorm() > 0 ||
                              (w.angular_velocity.squaredNorm() > 0 && !w.spins_in_place());
            return frame;
          },
          py::arg("index"))
      .def("run", &Level::run, py::arg("steps"), py::arg("stats") = true,
           py::call_guard<py::gil_scoped_release>())
      .def_property("record_contacts", &Level::record_contacts, &Level::set_record_contacts)
      .def("mark_positions_changed", &Level::mark_positions_changed)
      .def("mark_velocities_changed", &Level::mark_velocities_changed)
      .def_property_readonly("step", &Level::step)
      .def_property_readonly("time", &Level::time)
      .def_property_readonly("time_step", &Level::time_step)
      .def_property_readonly("skin", &Level::skin)
      .def_property_readonly("num_owned", [](Level& l) { return l.particles().n_owned(); })
      .def_property_readonly("num_ghosts", [](Level& l) { return l.particles().n_ghost(); })
      .def_property_readonly("lost_particles", &Level::lost_particles)
      .def_property_readonly("lost_mass", &Level::lost_mass)
      .def_property_readonly("lost_log_size",
                             [](Level& l) { return static_cast<py::ssize_t>(l.lost_log().size()); })
      .def(
          "lost_log",
          [](Level& l, py::ssize_t start) {
            const auto& log = l.lost_log();
            const auto from =
                std::min(static_cast<std::size_t>(std::max<py::ssize_t>(start, 0)), log.size());
            return py::array_t<GlobalId>(static_cast<py::ssize_t>(log.size() - from),
                                         log.data() + from);
          },
          py::arg("start") = 0)
      .def(
          "set_guards",
          [](Level& l, bool enabled, Real max_step_displacement, Real max_overlap) {
            l.set_guards({enabled, max_step_displacement, max_overlap});
          },
          py::arg("enabled"), py::arg("max_step_displacement"), py::arg("max_overlap"))
      .def_property_readonly("guard_tripped", &Level::guard_tripped)
      .def_property_readonly("rebuilds", &Level::rebuilds)
      .def_property_readonly("rebuild_seconds", &Level::rebuild_seconds)
      .def_property_readonly("halo_seconds", &Level::halo_seconds)
      .def("kinetic_energy", &Level::kinetic_energy)
      .def("smallest_rayleigh_time", &Level::smallest_rayleigh_time)
      .def("last_contact_count", [](Level& l) { return l.last_stats().contacts; })
      .def("last_max_overlap_ratio", [](Level& l) { return l.last_stats().max_overlap_ratio; })
      .def("contacts",
           [](Level& l) {
             const auto& rec = l.last_stats().records;
             const py::ssize_t n = static_cast<py::ssize_t>(rec.size());
             py::array_t<GlobalId> id_i(n), id_j(n);
             py::array_t<Real> overlap(n);
             py::array_t<Real> normal({n, py::ssize_t(3)}), force({n, py::ssize_t(3)});
             auto a = id_i.mutable_unchecked<1>();
             auto b = id_j.mutable_unchecked<1>();
             auto o = overlap.mutable_unchecked<1>();
             auto nn = normal.mutable_unchecked<2>();
             auto ff = force.mutable_unchecked<2>();
             for (py::ssize_t k = 0; k < n; ++k) {
               a(k) = rec[k].id_i;
               b(k) = rec[k].id_j;
               o(k) = rec[k].overlap;
               for (int c = 0; c < 3; ++c) {
                 nn(k, c) = rec[k].normal[c];
                 ff(k, c) = rec[k].force[c];
               }
             }
             py::dict d;
             d["id_i"] = id_i;
             d["id_j"] = id_j;
             d["overlap"] = overlap;
             d["normal"] = normal;
             d["force"] = force;
             return d;
           })
      .def("neighbor_pairs",
           [](Level& l) {
             const auto pairs = l.neighbor_pairs();
             py::array_t<GlobalId> out({static_cast<py::ssize_t>(pairs.size()), py::ssize_t(2)});
             auto o = out.mutable_unchecked<2>();
             for (std::size_t k = 0; k < pairs.size(); ++k) {
               o(k, 0) = pairs[k][0];
               o(k, 1) = pairs[k][1];
             }
             return out;
           })
      .def(
          "view",
          [](Level& l, const std::string& name) -> py::array {
            ParticleStore& ps = l.particles();
            const Index n = ps.n_owned();
            if (name == "position") return view<Vec3, Real>(ps.position, n, {0, 3});
            if (name == "velocity") return view<Vec3, Real>(ps.velocity, n, {0, 3});
            if (name == "angular_velocity") return view<Vec3, Real>(ps.angular_velocity, n, {0, 3});
            if (name == "force") return view<Vec3, Real>(ps.force, n, {0, 3});
            if (name == "torque") return view<Vec3, Real>(ps.torque, n, {0, 3});
            if (name == "radius") return view<Real, Real>(ps.radius, n, {0});
            if (name == "mass") return view<Real, Real>(ps.mass, n, {0});
            if (name == "id") return view<GlobalId, GlobalId>(ps.id, n, {0});
            if (name == "material") return view<std::int32_t, std::int32_t>(ps.material, n, {0});
            throw py::value_error("unknown particle array '" + name + "'");
          },
          py::arg("name"));
}
