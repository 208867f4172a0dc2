// Numpy (V, 3) vertex and (T, 3) triangle arrays to a TriangleMesh (mesh walls, mesh regions).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>

#include "geometry/triangle_mesh.hpp"

namespace grainscale {

using VertexArray = pybind11::array_t<Real, pybind11::array::c_style | pybind11::array::forcecast>;
using TriangleArray =
    pybind11::array_t<std::int32_t, pybind11::array::c_style | pybind11::array::forcecast>;

inline TriangleMesh mesh_from_arrays(const VertexArray& vertices, const TriangleArray& triangles) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3)
    throw pybind11::value_error("Mesh.vertices must have shape (V, 3)");
  if (triangles.ndim() != 2 || triangles.shape(1) != 3)
    throw pybind11::value_error("Mesh.triangles must have shape (T, 3)");
  TriangleMesh mesh;
  const Real* v = vertices.data();
  for (pybind11::ssize_t k = 0; k < vertices.shape(0); ++k)
    mesh.vertices.emplace_back(v[3 * k], v[3 * k + 1], v[3 * k + 2]);
  const std::int32_t* t = triangles.data();
  for (pybind11::ssize_t k = 0; k < triangles.shape(0); ++k)
    mesh.triangles.push_back({t[3 * k], t[3 * k + 1], t[3 * k + 2]});
  return mesh;
}

}  // namespace grainscale
