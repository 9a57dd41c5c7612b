// compare(): two surfaces measured as `scan2lod compare --json` measures them
// (measure/compare_files.h), the same JSON object as a dict.
#include <scan2lod/measure/compare_files.h>
#include <scan2lod/measure/comparison_json.h>
#include <scan2lod/python/bindings.h>
#include <scan2lod/python/errors.h>
#include <scan2lod/python/progress.h>

#include <pybind11/stl.h>

#include <optional>

namespace scan2lod::python {
namespace {

bool is_mesh(const py::handle& side) { return py::isinstance<TriangleMesh>(side); }

py::dict compare(const py::object& a, const py::object& b, std::optional<std::int64_t> samples, std::uint64_t seed,
                 const py::object& progress) {
  CompareOptions options;
  if (samples) {
    if (*samples <= 0) throw py::value_error("samples must be > 0, got " + std::to_string(*samples));
    options.samples = std::size_t(*samples);
  }
  options.seed = seed;
  SurfaceComparison c;
  if (is_mesh(a) && is_mesh(b)) {
    const auto& mesh_a = a.cast<const TriangleMesh&>();
    const auto& mesh_b = b.cast<const TriangleMesh&>();
    c = with_progress(progress, [&] { return compare_named(mesh_a, mesh_b, options, "a", "b"); });
  } else if (!is_mesh(a) && !is_mesh(b)) {
    const std::string path_a = path_text(a), path_b = path_text(b);
    c = reading_files({path_a, path_b}, [&] {
      return with_progress(progress, [&] {
        const MeshPair meshes = read_in_one_frame(path_a, path_b);
        return compare_named(meshes.a, meshes.b, options, path_a, path_b);
      });
    });
  } else {
    throw py::type_error("compare() takes two Mesh objects or two paths");
  }
  return py::module_::import("json").attr("loads")(comparison_json(c).dump());
}

}  // namespace

void bind_compare(py::module_& m) {
  m.def("compare", &compare, py::arg("a"), py::arg("b"), py::arg("samples") = py::none(), py::kw_only(),
        py::arg("seed") = 1, py::arg("progress") = py::none(),
        R"doc(
compare(a, b, samples=None, *, seed=1, progress=None) -> dict

Surface distances both ways and both meshes' topology, as `scan2lod compare
--json` prints them: {"a_to_b": {"mean", "rms", "p95", "max", "samples"},
"b_to_a": {...}, "diagonal": B's bounding-box diagonal, "a": {...}, "b": {...}}.
`a` and `b` are two Mesh objects or two mesh paths; `samples` per direction
(None: 10 per triangle of the sampled mesh, at least 100000).
)doc");
}

}  // namespace scan2lod::python
