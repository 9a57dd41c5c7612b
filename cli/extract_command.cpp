// scan2lod extract: one mesh out of a .mco model, taken by reference from
// either LOD structure (lod/lod_model.h): by percent, triangle budget,
// object-space error, camera, or (octree) priority number.
#include <scan2lod/cli/byte_size.h>
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/outputs.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/level_chain.h>
#include <scan2lod/lod/level_choice.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/percent_shortfall.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>

namespace scan2lod::cli {
namespace {

// "EX,EY,EZ,TX,TY,TZ,UX,UY,UZ" -> camera; throws InputError naming --camera.
// Whether it has a frame is level_request()'s to check (lod/level_choice.h).
CameraView parse_camera(const std::string& text) {
  std::vector<float> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      v.push_back(std::stof(item, &used));
      if (used != item.size() || !std::isfinite(v.back())) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError("", "--camera needs 9 numbers EX,EY,EZ,TX,TY,TZ,UX,UY,UZ; '" + item + "' is not a number");
    }
  }
  if (v.size() != 9)
    throw InputError("", "--camera needs 9 numbers EX,EY,EZ,TX,TY,TZ,UX,UY,UZ, got " + std::to_string(v.size()));
  CameraView c;
  c.eye = Vec3f(v[0], v[1], v[2]);
  c.target = Vec3f(v[3], v[4], v[5]);
  c.up = Vec3f(v[6], v[7], v[8]);
  return c;
}

}  // namespace

void add_extract_command(CLI::App& app) {
  struct Args {
    std::string model, output, structure, camera, cache = "256M";
    double percent = 0, error = 0, fov = 45, pixel_error = 1;
    long long triangles = 0, priority = 0;
    int height = 1080;
    bool json = false, no_quantize = false, at_most = false, stored_cut = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("extract", "One level of detail of a .mco model -> mesh");
  cmd->add_option("model", args->model, "Model written by scan2lod build (.mco)")->required();
  cmd->add_option("-o,--output", args->output, "Output mesh (.ply .obj .stl .off .vtp .glb .gltf)")->required();
  cmd->add_flag("--no-quantize", args->no_quantize, "glTF: 32-bit float positions and normals");
  cmd->add_option("--structure", args->structure,
                  "clusters or octree (default: clusters when the model has them)")
      ->check(CLI::IsMember(structure_names(), CLI::ignore_case));
  CLI::Option* percent = cmd->add_option(
      "--percent", args->percent,
      "0 to 100: octree, the first P % of the LOD array; clusters, P % of the full triangle count (a warning "
      "when no level is within 10 % of it)");
  CLI::Option* triangles =
      cmd->add_option("--triangles", args->triangles,
                      "A level within 10 % of T triangles: the finest with at most T, or, where that falls more than "
                      "10 % short, the next when it has at most 10 % more. Clusters: a stored cut of at most 1.25 T "
                      "refined to T by edge collapse where one has more than T");
  CLI::Option* at_most = cmd->add_flag("--at-most", args->at_most, "With --triangles: never more than T triangles");
  at_most->needs(triangles);
  CLI::Option* stored_cut = cmd->add_flag("--stored-cut", args->stored_cut,
                "Clusters, with --percent or --triangles: the stored cut the count gets, not refined to it");
  CLI::Option* error = cmd->add_option("--error", args->error,
                                       "Clusters: the cut at this object-space error (model units)");
  CLI::Option* camera = cmd->add_option("--camera", args->camera,
                                        "Clusters: the cut seen from EX,EY,EZ looking at TX,TY,TZ with up UX,UY,UZ");
  // Given without --camera they would change nothing: a usage error, not a silent ignore.
  const std::vector<CLI::Option*> camera_flags = {
      cmd->add_option("--fov", args->fov, "With --camera only: vertical field of view in degrees, in (0, 180)")
          ->default_val(45),
      cmd->add_option("--height", args->height, "With --camera only: viewport height in pixels")->default_val(1080),
      cmd->add_option("--pixel-error", args->pixel_error, "With --camera only: largest error on screen, in pixels")
          ->default_val(1)};
  cmd->add_option("--cache", args->cache,
                  "Clusters: pages of the model held in memory at most (default 256M); a cut reads only the pages "
                  "of the clusters it draws")
      ->check(size_problem);
  CLI::Option* priority =
      cmd->add_option("--priority", args->priority, "Octree: the level after N expansions (0: the root's mesh)");
  cmd->add_flag("--json", args->json,
                "Print {\"structure\", \"triangles\", \"vertices\", \"clusters\", \"priority\", \"error\", "
                "\"select_seconds\", \"extract_seconds\"} as JSON, with \"refined_from\" when the cut was refined to the count, \"warnings\" when there are any and "
                "\"read\" {\"pages\", \"bytes\", \"file_bytes\"} when the cut was read page by page");
  cmd->callback([args, percent, triangles, error, camera, priority, camera_flags, stored_cut] {
    if (stored_cut->count() && !percent->count() && !triangles->count())
      throw CLI::ValidationError("--stored-cut", "applies to --percent and --triangles only; other requests are "
                                                 "not refined, so it would be ignored");
    for (const CLI::Option* flag : camera_flags)
      if (flag->count() && !camera->count()) {
        const CLI::Option* asked = percent->count() ? percent : triangles->count() ? triangles
                                                              : error->count()   ? error
                                                              : priority->count() ? priority
                                                                                 : nullptr;
        if (asked)
          throw CLI::ValidationError(flag->get_name(), "applies to --camera only; " + asked->get_name() +
                                                           " takes no camera, so it would be ignored");
      }
    LevelChoice choice;
    if (percent->count()) choice.percent = args->percent;
    if (triangles->count()) choice.triangles = args->triangles;
    choice.at_most = args->at_most;
    choice.stored_cut = args->stored_cut;
    if (error->count()) choice.error = args->error;
    if (priority->count()) choice.priority = args->priority;
    if (camera->count()) {
      CameraView view = parse_camera(args->camera);
      view.fov_degrees = float(args->fov);
      view.height = args->height;
      choice.camera = view;
    }
    choice.pixel_error = args->pixel_error;
    const LevelRequest request = level_request(choice, OptionSpelling::kCommandLine);
    check_mesh_output(args->output);
    refuse_overwriting_inputs(args->output, {args->model});

    // Cluster cuts read only the pages they draw when the file has pages
    // (format 4.6); the octree, and older files, are read whole.
    const bool octree = args->structure == "octree" || (args->structure.empty() && priority->count());
    std::optional<LodModel> paged;
    if (!octree) paged = open_paged_model(args->model, std::uint64_t(parse_bytes(args->cache)));
    const LodModel model = paged ? std::move(*paged) : load_model(args->model);
    check_mesh_output(args->output, model.origin, model_bounds(model));
    // A priority number is the octree's own: it picks the octree when no structure is named.
    const LodStructure structure = structure_named(
        model, args->structure.empty() && priority->count() ? std::string("octree") : args->structure, args->model);
    LevelExtractor extractor(model, structure);
    const LevelCut& cut = extract_level_to_deliver(&extractor, request, args->model);
    Warnings warnings(args->json);
    if (const std::string shortfall = budget_shortfall(extractor, request, cut); !shortfall.empty())
      warnings(shortfall);
    if (percent->count())
      if (const std::string shortfall = percent_shortfall(model, structure, "--percent", args->percent, cut);
          !shortfall.empty())
        warnings(shortfall);
    const auto start = std::chrono::steady_clock::now();
    const TriangleMesh mesh = compact_level(model, cut.triangles);
    const double compact_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    MeshWriteOptions write;
    write.quantize = !args->no_quantize;
    write.generator = std::string("scan2lod ") + SCAN2LOD_VERSION;
    write.origin = model.origin;  // back in the inputs' frame (georeferenced inputs)
    write_mesh(args->output, mesh, write);

    if (args->json) {
      nlohmann::ordered_json j = {{"structure", structure_name(structure)},
                                  {"triangles", mesh.triangles.size()},
                                  {"vertices", mesh.positions.size()}};
      if (structure == LodStructure::kClusters) {
        j["clusters"] = cut.clusters;
        j["error"] = cut.error;
        if (cut.refined_from > 0) j["refined_from"] = cut.refined_from;
      } else {
        j["priority"] = cut.priority;
      }
      j["percent"] = cut.percent;
      j["select_seconds"] = cut.select_seconds;
      j["extract_seconds"] = cut.extract_seconds + compact_seconds;
      if (model.clusters && model.clusters->paged) {
        const PageStats& read = model.clusters->paged->stats();
        j["read"] = {{"pages", read.pages_read},
                     {"bytes", read.head_bytes + read.page_bytes_read},
                     {"file_bytes", std::filesystem::file_size(args->model)}};
      }
      if (!warnings.kept().empty()) j["warnings"] = warnings.kept();
      std::printf("%s\n", j.dump(2).c_str());
    } else if (structure == LodStructure::kClusters) {
      say("clusters: %zu clusters, %zu triangles (%.1f %%), %zu vertices, error %.3g, selected in %.3f ms, "
                  "extracted in %.2f ms -> %s\n",
                  cut.clusters, mesh.triangles.size(), cut.percent, mesh.positions.size(), cut.error,
                  cut.select_seconds * 1e3, (cut.extract_seconds + compact_seconds) * 1e3, args->output.c_str());
      if (cut.refined_from > 0)
        say("refined by edge collapse from a stored cut of %zu triangles (--stored-cut: that cut as it is)\n",
            cut.refined_from);
      if (model.clusters->paged) {
        const PageStats& read = model.clusters->paged->stats();
        say("read %llu pages page by page: %.1f of the model's %.1f MB\n", (unsigned long long)read.pages_read,
            double(read.head_bytes + read.page_bytes_read) / 1e6, double(std::filesystem::file_size(args->model)) / 1e6);
      }
    } else {
      say("octree: priority %zu (%.1f %%), %zu triangles, %zu vertices, extracted in %.2f ms -> %s\n",
                  cut.priority, cut.percent, mesh.triangles.size(), mesh.positions.size(),
                  (cut.extract_seconds + compact_seconds) * 1e3, args->output.c_str());
    }
  });
}

}  // namespace scan2lod::cli
