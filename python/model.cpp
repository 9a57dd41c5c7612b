// Model: a LOD model (lod/lod_model.h) built, loaded, saved, and cut into
// levels, as `scan2lod build`, `extract` and the .mco file hold them.
#include <scan2lod/acquisition/mesh_points.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/level_chain.h>
#include <scan2lod/lod/level_choice.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/percent_shortfall.h>
#include <scan2lod/lod/structure.h>
#include <scan2lod/pipeline/build_model.h>
#include <scan2lod/python/bindings.h>
#include <scan2lod/python/errors.h>
#include <scan2lod/python/keyword_options.h>
#include <scan2lod/python/points.h>
#include <scan2lod/python/progress.h>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdlib>
#include <filesystem>
#include <optional>

namespace scan2lod::python {
namespace {

struct Model {
  std::shared_ptr<const LodModel> model;
  std::string source;  // the file it came from, or "model", for messages
};

// A camera (eye, target, up) of three 3-vectors; fov and height as the CLI's.
CameraView camera_of(const py::handle& camera, double fov, int height) {
  const auto parts = py::cast<std::vector<std::vector<float>>>(camera);
  if (parts.size() != 3 || parts[0].size() != 3 || parts[1].size() != 3 || parts[2].size() != 3)
    throw py::value_error("camera must be (eye, target, up), three points of 3 numbers each");
  CameraView view;
  view.eye = Vec3f(parts[0][0], parts[0][1], parts[0][2]);
  view.target = Vec3f(parts[1][0], parts[1][1], parts[1][2]);
  view.up = Vec3f(parts[2][0], parts[2][1], parts[2][2]);
  view.fov_degrees = float(fov);
  view.height = height;
  return view;
}

py::object extract(const Model& self, std::optional<std::int64_t> triangles, std::optional<double> percent,
                   std::optional<double> error, const py::object& camera, double pixel_error,
                   std::optional<std::string> structure, double fov, int height, bool at_most,
                   std::optional<std::int64_t> priority, bool stored_cut) {
  LevelChoice choice;
  choice.triangles = triangles;
  choice.at_most = at_most;
  choice.stored_cut = stored_cut;
  choice.percent = percent;
  choice.error = error;
  choice.priority = priority;
  if (!camera.is_none()) choice.camera = camera_of(camera, fov, height);
  choice.pixel_error = pixel_error;
  const LevelRequest request = level_request(choice, OptionSpelling::kKeywords);
  const LodModel& model = *self.model;
  // A priority number is the octree's own: it picks the octree when no structure is named.
  const LodStructure chosen =
      structure_named(model, structure ? *structure : priority ? std::string("octree") : std::string(), self.source);
  std::vector<std::string> shortfalls;  // as `scan2lod extract` warns of them
  TriangleMesh mesh = [&] {
    py::gil_scoped_release released;
    LevelExtractor extractor(model, chosen);
    const LevelCut& cut = extract_level_to_deliver(&extractor, request, self.source);
    shortfalls.push_back(budget_shortfall(extractor, request, cut));
    if (percent) shortfalls.push_back(percent_shortfall(model, chosen, "percent", *percent, cut));
    return compact_level(model, cut.triangles);
  }();
  for (const std::string& shortfall : shortfalls)
    if (!shortfall.empty()) warn_all({shortfall});
  return mesh_object(std::move(mesh));
}

// A temporary folder for a build's bricks and spools, removed with it.
struct WorkFolder {
  std::string path;
  WorkFolder() {
    std::string pattern = (std::filesystem::temp_directory_path() / "scan2lod-build-XXXXXX").string();
    if (mkdtemp(pattern.data())) path = pattern;
  }
  ~WorkFolder() {
    std::error_code ec;
    if (!path.empty()) std::filesystem::remove_all(path, ec);
  }
};

Model build(const py::object& inputs, const py::object& structures, const py::object& memory, int resolution,
            int threads, const py::object& progress, const py::kwargs& keywords) {
  KeywordOptions given(keywords, "build");
  BuildOptions options;
  options.reconstruct = given.reconstruct(resolution, threads);
  given.take("unregistered", &options.acquisition.unregistered);
  given.take("work_dir", &options.work_dir);
  given.refuse_unknown();
  options.acquisition.threads = threads;
  if (!memory.is_none()) {
    options.memory_bytes = memory.cast<double>();
    if (!(options.memory_bytes > 0))
      throw py::value_error("memory must be a number of bytes > 0, got " + py::repr(memory).cast<std::string>());
  }
  std::vector<std::string> names = py::isinstance<py::str>(structures)
                                       ? std::vector<std::string>{structures.cast<std::string>()}
                                       : structures.cast<std::vector<std::string>>();
  options.octree = options.clusters = false;
  for (const std::string& name : names) {
    if (name == "octree") options.octree = true;
    else if (name == "clusters") options.clusters = true;
    else throw py::value_error("structures: unknown structure '" + name + "'; expected clusters or octree");
  }
  WorkFolder work;
  if (options.work_dir.empty()) options.work_dir = work.path;

  Model built;
  built.source = "model";
  if (py::isinstance<TriangleMesh>(inputs)) {
    // The mesh's own triangles are the clusters' full detail, as for a mesh file.
    const auto mesh = inputs.cast<std::shared_ptr<TriangleMesh>>();
    built.model = std::make_shared<LodModel>(with_progress(progress, [&] {
      const OrientedPoints points = options.octree ? mesh_to_oriented_points(*mesh) : OrientedPoints();
      return build_model(points, options.clusters ? mesh.get() : nullptr, options);
    }));
    return built;
  }
  std::vector<std::string> paths;
  if (py::isinstance<py::str>(inputs) || py::hasattr(inputs, "__fspath__"))
    paths.push_back(path_text(inputs));
  else
    for (const py::handle& path : inputs) paths.push_back(path_text(path));
  if (paths.empty()) throw py::value_error("build() needs a Mesh or at least one path");
  BuildReport report;
  built.model = std::make_shared<LodModel>(reading_files(
      paths, [&] { return with_progress(progress, [&] { return build_model(paths, options, &report); }); }));
  warn_all(report.warnings);
  return built;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<Model>(m, "Model", R"doc(
A LOD model: one shared vertex array and one or both LOD structures, the
cluster hierarchy (Cignoni et al., *Batched Multi-Triangulation*, 2005) and
the prioritized marching-cube octree (Lee, *Efficient LOD Model Generation of
3D Objects using Prioritized Marching Cube Octree*, 2007).
)doc")
      .def_property_readonly("structures",
                             [](const Model& self) {
                               py::list names;
                               if (self.model->has(LodStructure::kClusters)) names.append("clusters");
                               if (self.model->has(LodStructure::kOctree)) names.append("octree");
                               return py::tuple(names);
                             })
      .def("extract", &extract, py::arg("triangles") = py::none(), py::arg("percent") = py::none(),
           py::arg("error") = py::none(), py::arg("camera") = py::none(), py::arg("pixel_error") = 1.0,
           py::arg("structure") = py::none(), py::kw_only(), py::arg("fov") = 45.0, py::arg("height") = 1080,
           py::arg("at_most") = false, py::arg("priority") = py::none(), py::arg("stored_cut") = false,
           R"doc(
extract(triangles=None, percent=None, error=None, camera=None, pixel_error=1.0, structure=None, *, fov=45, height=1080, at_most=False, priority=None, stored_cut=False) -> Mesh

One level, as `scan2lod extract` takes it: exactly one of a triangle budget
(met within 10 %; at_most: never over it), a percent, an object-space error,
a camera (eye, target, up) seen with a vertical fov in degrees on a viewport
`height` pixels high whose error is at most `pixel_error` pixels, or an
octree priority. `structure` is "clusters" or "octree" (default: the
clusters when the model has them). The clusters serve a count from a stored
cut of at most 1.25 times it, refined to it by edge collapse; stored_cut
gives the stored cut as it is.
)doc")
      .def(
          "save",
          [](const Model& self, const std::filesystem::path& path) {
            const std::string name = path.string();
            writing_file(
                name, [&] { check_model_output(name); },
                [&] {
                  py::gil_scoped_release released;
                  save_model(name, *self.model);
                });
          },
          py::arg("path"), "Writes the model to a .mco file, as `scan2lod build -o` does.")
      .def("__repr__", [](const Model& self) {
        std::string text = "<scan2lod.Model: " + std::to_string(self.model->vertices.size()) + " vertices";
        for (const StructureKind* kind : registered_structures())
          if (kind->present(*self.model))
            text += std::string(", ") + kind->name + " of " +
                    std::to_string(LevelExtractor(*self.model, kind->id).full_triangles()) + " triangles";
        return text + ">";
      });

  m.def("build", &build, py::arg("mesh_or_paths"), py::arg("structures") = py::make_tuple("clusters"),
        py::arg("memory") = py::none(), py::kw_only(), py::arg("resolution") = 256, py::arg("threads") = 0,
        py::arg("progress") = py::none(),
        R"doc(
build(mesh_or_paths, structures=("clusters",), memory=None, *, resolution=256, threads=0, progress=None, **options) -> Model

Builds a LOD model as `scan2lod build` does: from a Mesh (its own triangles are
the clusters' full detail) or from a path or paths of what load_points()
reads. `structures`: "clusters" and/or "octree". `memory`, in bytes, is the
budget (None: what the machine has available); a reconstruction over it runs
brick by brick in a temporary folder (or `work_dir`). `options` are
reconstruct()'s, and `unregistered`.
)doc");

  m.def(
      "load",
      [](const std::filesystem::path& path) {
        const std::string name = path.string();
        Model loaded;
        loaded.source = name;
        loaded.model = std::make_shared<LodModel>(reading_files({name}, [&] {
          py::gil_scoped_release released;
          return load_model(name);
        }));
        return loaded;
      },
      py::arg("path"), "Reads a .mco model written by Model.save() or `scan2lod build`.");
}

}  // namespace scan2lod::python
