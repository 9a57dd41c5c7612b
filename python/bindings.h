// The Python package's parts, each adding its names to the module
// (module.cpp calls them in this order).
#pragma once

#include <scan2lod/core/types.h>

#include <pybind11/pybind11.h>

#include <memory>
#include <string>

namespace scan2lod::python {

namespace py = pybind11;

void bind_mesh(pybind11::module_& m);         // Mesh, read_mesh, write_mesh (mesh.cpp)
void bind_points(pybind11::module_& m);       // load_points (points.cpp)
void bind_reconstruct(pybind11::module_& m);  // reconstruct (reconstruct.cpp)
void bind_model(pybind11::module_& m);        // Model, build, load (model.cpp)
void bind_compare(pybind11::module_& m);      // compare (compare.cpp)

// A path given as str or os.PathLike, as text (points.cpp).
std::string path_text(const pybind11::handle& path);

// A Mesh for Python, owning `mesh`.
pybind11::object mesh_object(TriangleMesh&& mesh);

}  // namespace scan2lod::python
