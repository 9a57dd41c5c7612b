// Mesh: a TriangleMesh (core/types.h) whose arrays Python sees as numpy views
// of the mesh's own vectors, and its files (io/mesh_file.h).
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/python/bindings.h>
#include <scan2lod/python/errors.h>
#include <scan2lod/python/numpy_arrays.h>

#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <string>

namespace scan2lod::python {
namespace {

// Rows of `source` into `*into`, resized to match; `what` names the argument.
template <typename Row, typename Element>
void import_rows(const py::handle& source, std::vector<Row>* into, const char* casting, const std::string& what) {
  const py::array rows = require_rows(source, 3, what);
  into->resize(std::size_t(rows.shape(0)));
  copy_rows<Element>(rows, into->data(), into->size(), 3, casting, what);
}

// Triangles name vertices: integers in [0, vertices). Checked by numpy
// before the copy, so that no index wraps in the cast to int32.
void import_triangles(const py::handle& source, std::size_t vertices, std::vector<Triangle>* into) {
  const py::array rows = require_rows(source, 3, "triangles");
  const char kind = rows.dtype().kind();
  if (kind != 'i' && kind != 'u')
    throw py::type_error("triangles must hold integers, got dtype " + py::str(rows.dtype()).cast<std::string>());
  const py::int_ count(vertices);
  if (rows.shape(0) > 0 && (rows.attr("min")() < py::int_(0) || rows.attr("max")() >= count)) {
    const py::object flat = rows.attr("reshape")(-1);
    const py::object outside = flat.attr("__lt__")(0).attr("__or__")(flat.attr("__ge__")(count));
    const py::ssize_t at = py::module_::import("numpy").attr("flatnonzero")(outside)[py::int_(0)].cast<py::ssize_t>();
    throw py::value_error("triangle " + std::to_string(at / 3) + " names vertex " +
                          py::str(flat[py::int_(at)]).cast<std::string>() + "; expected 0 to " +
                          std::to_string((long long)vertices - 1) + " (the mesh has " + std::to_string(vertices) +
                          " vertices)");
  }
  into->resize(std::size_t(rows.shape(0)));
  copy_rows<std::uint32_t>(rows, into->data(), into->size(), 3, "unsafe", "triangles");
}

std::shared_ptr<TriangleMesh> mesh_from_arrays(const py::object& vertices, const py::object& triangles,
                                               const py::object& normals, const py::object& colors) {
  auto mesh = std::make_shared<TriangleMesh>();
  import_rows<Vec3f, float>(vertices, &mesh->positions, "same_kind", "vertices");
  import_triangles(triangles, mesh->positions.size(), &mesh->triangles);
  if (!normals.is_none()) {
    import_rows<Vec3f, float>(normals, &mesh->normals, "same_kind", "normals");
    if (mesh->normals.size() != mesh->positions.size())
      throw py::value_error("normals must have one row per vertex: " + std::to_string(mesh->normals.size()) +
                            " rows for " + std::to_string(mesh->positions.size()) + " vertices");
  }
  if (!colors.is_none()) {
    import_rows<Rgb, std::uint8_t>(colors, &mesh->colors, "unsafe", "colors");
    if (mesh->colors.size() != mesh->positions.size())
      throw py::value_error("colors must have one row per vertex: " + std::to_string(mesh->colors.size()) +
                            " rows for " + std::to_string(mesh->positions.size()) + " vertices");
  }
  return mesh;
}

}  // namespace

py::object mesh_object(TriangleMesh&& mesh) { return py::cast(std::make_shared<TriangleMesh>(std::move(mesh))); }

void bind_mesh(py::module_& m) {
  py::class_<TriangleMesh, std::shared_ptr<TriangleMesh>>(m, "Mesh", R"doc(
An indexed triangle mesh. Its arrays are numpy views of the mesh's own memory
(no copy): vertices float32 (n, 3), triangles uint32 (m, 3), counter-clockwise
seen from outside; normals float32 (n, 3) and colors uint8 (n, 3), or None.
)doc")
      .def(py::init(&mesh_from_arrays), py::arg("vertices"), py::arg("triangles"), py::arg("normals") = py::none(),
           py::arg("colors") = py::none(),
           "Copies the arrays once into the mesh (any numeric dtype numpy casts to float32; integer triangles).")
      .def_property_readonly(
          "vertices",
          [](py::object self) {
            const auto& mesh = self.cast<const TriangleMesh&>();
            return rows_view<float>(mesh.positions.data(), mesh.positions.size(), 3, self);
          })
      .def_property_readonly(
          "triangles",
          [](py::object self) {
            const auto& mesh = self.cast<const TriangleMesh&>();
            return rows_view<std::uint32_t>(mesh.triangles.data(), mesh.triangles.size(), 3, self);
          })
      .def_property_readonly("normals",
                             [](py::object self) -> py::object {
                               const auto& mesh = self.cast<const TriangleMesh&>();
                               if (mesh.normals.empty()) return py::none();
                               return rows_view<float>(mesh.normals.data(), mesh.normals.size(), 3, self);
                             })
      .def_property_readonly("colors",
                             [](py::object self) -> py::object {
                               const auto& mesh = self.cast<const TriangleMesh&>();
                               if (mesh.colors.empty()) return py::none();
                               return rows_view<std::uint8_t>(mesh.colors.data(), mesh.colors.size(), 3, self);
                             })
      .def("__repr__", [](const TriangleMesh& mesh) {
        return "<scan2lod.Mesh: " + std::to_string(mesh.positions.size()) + " vertices, " +
               std::to_string(mesh.triangles.size()) + " triangles>";
      });

  m.def(
      "read_mesh",
      [](const std::filesystem::path& path) {
        const std::string name = path.string();
        TriangleMesh mesh = reading_files({name}, [&] {
          py::gil_scoped_release released;
          return read_mesh(name);
        });
        return mesh_object(std::move(mesh));
      },
      py::arg("path"),
      "Reads a .ply, .obj, .off, .stl, .vtp, .glb or .gltf mesh (as `scan2lod` reads its inputs).");

  m.def(
      "write_mesh",
      [](const std::filesystem::path& path, const TriangleMesh& mesh) {
        const std::string name = path.string();
        writing_file(
            name, [&] { check_mesh_output(name); },
            [&] {
              py::gil_scoped_release released;
              MeshWriteOptions options;
              options.generator = std::string("scan2lod ") + SCAN2LOD_VERSION;
              write_mesh(name, mesh, options);
            });
      },
      py::arg("path"), py::arg("mesh"),
      "Writes `mesh` in the format its extension names (.ply .obj .off .stl .vtp .glb .gltf), as "
      "`scan2lod reconstruct -o` does.");
}

}  // namespace scan2lod::python
