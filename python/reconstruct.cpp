// reconstruct(): oriented points -> marching-cubes mesh, as `scan2lod
// reconstruct` makes it (reconstruct/marching_cubes.h), in core.
#include <scan2lod/acquisition/cloud_normals.h>
#include <scan2lod/python/bindings.h>
#include <scan2lod/python/keyword_options.h>
#include <scan2lod/python/points.h>
#include <scan2lod/python/progress.h>
#include <scan2lod/reconstruct/marching_cubes.h>

namespace scan2lod::python {
namespace {

// Memory in bytes, or None for what the machine has.
double memory_bytes(const py::object& memory) {
  if (memory.is_none()) return 0;
  const double bytes = memory.cast<double>();
  if (!(bytes > 0)) throw py::value_error("memory must be a number of bytes > 0, got " + py::repr(memory).cast<std::string>());
  return bytes;
}

py::object reconstruct_points(const py::object& points, const py::object& normals, int resolution, int threads,
                              const py::object& memory, const py::object& progress, const py::kwargs& keywords) {
  KeywordOptions given(keywords, "reconstruct");
  ReconstructOptions options = given.reconstruct(resolution, threads);
  given.refuse_unknown();
  options.memory_limit = memory_bytes(memory);
  const PointsArgument argument = points_argument(points, normals);
  Reconstruction r = with_progress(progress, [&] {
    std::shared_ptr<const OrientedPoints> set = argument.loaded;
    if (!set) {
      CloudNormalOptions estimate;
      estimate.threads = threads;
      set = std::make_shared<OrientedPoints>(cloud_to_oriented_points(*argument.cloud, estimate));
    }
    return reconstruct(*set, options);
  });
  warn_all(r.warnings);
  if (r.mesh.triangles.empty()) throw py::value_error(no_surface_message(r, resolution, "resolution"));
  return mesh_object(std::move(r.mesh));
}

}  // namespace

void bind_reconstruct(py::module_& m) {
  m.def("reconstruct", &reconstruct_points, py::arg("points"), py::arg("normals") = py::none(),
        py::arg("resolution") = 256, py::arg("threads") = 0, py::kw_only(), py::arg("memory") = py::none(),
        py::arg("progress") = py::none(),
        R"doc(
reconstruct(points, normals=None, resolution=256, threads=0, *, memory=None, progress=None, **options) -> Mesh

Signed distances and marching cubes over a sparse grid (Lee 2007, §4.2-4.3), as
`scan2lod reconstruct` does in core. `points` and `normals` are (n, 3) arrays
(normals outward; None: estimated, as for a point cloud without normals).
`resolution` is cubes per side (a power of two, 16 or more); `threads` 0 is all
cores; `memory` (bytes) refuses a resolution whose estimate exceeds it.
options, the command line's flags with underscores: margin, distance
("planes", "hoppe", "closest"), neighbours, max_distance, reach, min_piece,
max_hole, hole_rounds. `progress(stage, fraction)` is called as the work goes.
)doc");
}

}  // namespace scan2lod::python
