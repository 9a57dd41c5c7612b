// load_points(): what `scan2lod reconstruct` reads, as numpy arrays.
#include <scan2lod/python/points.h>

#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/python/bindings.h>
#include <scan2lod/python/errors.h>
#include <scan2lod/python/numpy_arrays.h>
#include <scan2lod/python/progress.h>

namespace scan2lod::python {
namespace {

// The load_points() set `points` and `normals` are the whole views of, or null.
std::shared_ptr<OrientedPoints> loaded_set(const py::array& points, const py::handle& normals) {
  std::shared_ptr<OrientedPoints> owner = owner_of<OrientedPoints>(points, kPointsOwner);
  if (!owner || normals.is_none() || !views_floats(points, owner->positions.data(), owner->size())) return nullptr;
  const py::array normal_rows = py::reinterpret_borrow<py::object>(normals);
  if (owner_of<OrientedPoints>(normal_rows, kPointsOwner) != owner ||
      !views_floats(normal_rows, owner->normals.data(), owner->size()))
    return nullptr;
  return owner;
}

}  // namespace

std::string path_text(const py::handle& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

PointsArgument points_argument(const py::handle& points, const py::handle& normals) {
  const py::array rows = require_rows(points, 3, "points");
  PointsArgument argument;
  if (std::shared_ptr<OrientedPoints> owner = loaded_set(rows, normals)) {
    argument.loaded = std::move(owner);
    return argument;
  }
  const std::size_t n = std::size_t(rows.shape(0));
  if (normals.is_none()) {
    auto cloud = std::make_shared<PointCloud>();
    cloud->positions.resize(n);
    copy_rows<float>(rows, cloud->positions.data(), n, 3, "same_kind", "points");
    cloud->source = "points";
    argument.cloud = std::move(cloud);
    return argument;
  }
  const py::array normal_rows = require_rows(normals, 3, "normals");
  if (std::size_t(normal_rows.shape(0)) != n)
    throw py::value_error("normals must have one row per point: " + std::to_string(normal_rows.shape(0)) +
                          " rows for " + std::to_string(n) + " points");
  auto set = std::make_shared<OrientedPoints>();
  set->positions.resize(n);
  set->normals.resize(n);
  copy_rows<float>(rows, set->positions.data(), n, 3, "same_kind", "points");
  copy_rows<float>(normal_rows, set->normals.data(), n, 3, "same_kind", "normals");
  argument.loaded = std::move(set);
  return argument;
}

void warn_all(const std::vector<std::string>& warnings) {
  for (const std::string& warning : warnings)
    if (PyErr_WarnEx(PyExc_UserWarning, warning.c_str(), 1) != 0) throw py::error_already_set();
}

void bind_points(py::module_& m) {
  m.def(
      "load_points",
      [](const py::args& paths, bool unregistered, int threads, py::object progress) {
        std::vector<std::string> inputs;
        for (const py::handle& path : paths) inputs.push_back(path_text(path));
        if (inputs.empty()) throw py::type_error("load_points() needs at least one path");
        if (threads < 0)
          throw py::value_error("threads: expected 0 (all cores) or a positive count, got " + std::to_string(threads));
        AcquisitionOptions options;
        options.unregistered = unregistered;
        options.threads = threads;
        AcquisitionReport report;
        auto set = std::make_shared<OrientedPoints>(reading_files(inputs, [&] {
          return with_progress(progress, [&] { return load_oriented_points(inputs, options, &report); });
        }));
        warn_all(report.warnings);
        const py::capsule owner = owner_capsule(set, kPointsOwner);
        return py::make_tuple(rows_view<float>(set->positions.data(), set->size(), 3, owner),
                              rows_view<float>(set->normals.data(), set->size(), 3, owner));
      },
      py::kw_only(), py::arg("unregistered") = false, py::arg("threads") = 0, py::arg("progress") = py::none(),
      R"doc(
load_points(*paths, unregistered=False, threads=0, progress=None) -> (points, normals)

Reads what `scan2lod reconstruct` reads (a Stanford .conf with its range-grid
PLYs, range scans, point clouds, meshes) into one set of oriented points in a
common frame: float32 (n, 3) positions and unit normals pointing outward.
Both arrays are views of the loaded set, which also keeps each point's sample
spacing and confidence; passed unchanged to reconstruct() or build(), they
reconstruct exactly what the command line does.
)doc");
}

}  // namespace scan2lod::python
