// scan2lod export: several levels of a .mco model in one process and one
// model load. glTF (.glb, .gltf) holds them as one MSFT_lod chain over shared
// vertices (io/gltf_file.h); a mesh format writes one file per level;
// --format 3dtiles writes a 3D Tiles 1.1 tileset folder (delivery/tileset.h),
// reading the model page by page when the file has pages, and the web page
// that views it (delivery/viewer_page.h).
#include <scan2lod/cli/byte_size.h>
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/outputs.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/delivery/tileset.h>
#include <scan2lod/delivery/viewer_page.h>
#include <scan2lod/io/gltf_file.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/level_chain.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/percent_shortfall.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>

namespace scan2lod::cli {
namespace {

namespace fs = std::filesystem;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<LevelRequest> requests_from(const std::vector<double>& percents, const std::vector<long long>& budgets,
                                        bool at_most, bool stored_cuts) {
  std::vector<LevelRequest> requests;
  for (double p : percents) {
    if (!(p > 0 && p <= 100)) throw InputError("", "--levels takes percentages in (0, 100], got " + std::to_string(p));
    requests.push_back(LevelRequest::at_percent(p));
  }
  for (long long t : budgets) {
    if (t < 1) throw InputError("", "--triangles takes budgets >= 1, got " + std::to_string(t));
    requests.push_back(at_most ? LevelRequest::at_most_triangles(t) : LevelRequest::at_triangles(t));
  }
  for (LevelRequest& r : requests) r.refine = !stored_cuts;
  return requests;
}

// `values` without repeats, first occurrences in order; warns once naming the
// repeats (`flag` names the list), as a level asked twice would be written twice.
template <typename T>
std::vector<T> without_repeats(const std::vector<T>& values, const std::string& flag, Warnings& warnings) {
  std::vector<T> kept;
  std::string repeats;
  for (const T& v : values) {
    if (std::find(kept.begin(), kept.end(), v) == kept.end()) {
      kept.push_back(v);
      continue;
    }
    std::ostringstream text;
    text << v;
    if (repeats.find(" " + text.str() + ",") == std::string::npos) repeats += " " + text.str() + ",";
  }
  if (!repeats.empty())
    warnings(flag + " repeats" + repeats.substr(0, repeats.size() - 1) + "; each level is written once");
  return kept;
}

const char* const kExportFormats = ".glb or .gltf (one file), or .ply, .obj, .off, .stl or .vtp (a file per level)";

// "out/bunny.ply" and level i -> "out/bunny_LOD<i>.ply".
std::string level_path(const std::string& output, const std::string& format, std::size_t i) {
  const fs::path p(output);
  return (p.parent_path() / (p.stem().string() + "_LOD" + std::to_string(i) + "." + format)).string();
}

// --format 3dtiles: the cluster hierarchy as a tileset folder.
struct TilesetArgs {
  std::string model, output, structure;
  long long tile_triangles = 16384;
  bool no_quantize = false, no_meshopt = false, json = false;
  std::uint64_t cache_bytes = 0;  // pages held at most, when the file has pages
};

void export_tileset(const TilesetArgs& args) {
  if (!args.structure.empty() && args.structure != "clusters")
    throw InputError(args.model, "--format 3dtiles tiles the cluster hierarchy; --structure " + args.structure +
                                     " cannot be tiled");
  if (args.tile_triangles < 1) throw InputError("", "--tile-triangles must be >= 1");
  refuse_overwriting_inputs(args.output, {args.model});
  auto start = std::chrono::steady_clock::now();
  // Read page by page when the file has pages (format 4.6), so that memory
  // is the cluster records, the cache and a tile; older files load whole.
  std::optional<LodModel> paged = open_paged_model(args.model, args.cache_bytes);
  const LodModel model = paged ? std::move(*paged) : load_model(args.model);
  const double load_seconds = seconds_since(start);
  TilesetOptions options;
  options.tiles.max_triangles = args.tile_triangles;
  options.glb.quantize = !args.no_quantize;
  options.glb.meshopt = !args.no_meshopt;
  options.glb.generator = std::string("scan2lod ") + SCAN2LOD_VERSION;
  if (ProgressSink sink = progress_sink(); sink && Progress::enabled())
    options.progress = [sink](const std::string& stage, double f) { sink("tiles: " + stage, f, f >= 1); };
  std::vector<std::string> page;
  options.add_files = [&page](const std::string& folder) { page = write_viewer_page(folder); };
  const TilesetReport r = write_tileset(model, args.output, options, args.model);
  const ClusterPages* pages = model.clusters ? model.clusters->paged.get() : nullptr;
  const std::uintmax_t file_bytes = fs::file_size(args.model);
  if (args.json) {
    nlohmann::ordered_json j = {{"structure", "clusters"},
                                {"format", "3dtiles"},
                                {"folder", args.output},
                                {"tiles", r.tiles},
                                {"content_tiles", r.content_tiles},
                                {"leaves", r.leaves},
                                {"depth", r.depth},
                                {"bytes", r.bytes},
                                {"largest_tile_bytes", r.largest_tile_bytes},
                                {"largest_tile_triangles", r.largest_tile_triangles},
                                {"root_triangles", r.root_triangles},
                                {"root_error", r.root_error},
                                {"triangles", r.triangles},
                                {"page", page}};
    j["seconds"] = {{"load", load_seconds}, {"plan", r.plan_seconds}, {"write", r.write_seconds}};
    if (pages)
      j["read"] = {{"pages", pages->stats().pages_read},
                   {"bytes", pages->stats().head_bytes + pages->stats().page_bytes_read},
                   {"file_bytes", file_bytes},
                   {"peak_cache_bytes", pages->stats().peak_resident_bytes}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  say("%zu tiles (%zu with content, depth %d): root %lld triangles at error %.3g, largest tile %lld triangles, "
      "%.2f MB (largest %.1f kB); load %.2f s, plan %.2f s, write %.2f s -> %s/tileset.json\n",
      r.tiles, r.content_tiles, r.depth, (long long)r.root_triangles, r.root_error,
      (long long)r.largest_tile_triangles, double(r.bytes) / 1e6, double(r.largest_tile_bytes) / 1e3, load_seconds,
      r.plan_seconds, r.write_seconds, args.output.c_str());
  if (pages)
    say("read %llu pages page by page: %.1f MB of a %.1f MB model, at most %.1f MB held\n",
        (unsigned long long)pages->stats().pages_read,
        double(pages->stats().head_bytes + pages->stats().page_bytes_read) / 1e6, double(file_bytes) / 1e6,
        double(pages->stats().peak_resident_bytes) / 1e6);
  if (!page.empty())
    say("page: %s/index.html; scan2lod serve %s, then open the address it prints\n", args.output.c_str(),
        args.output.c_str());
}

}  // namespace

void add_export_command(CLI::App& app) {
  struct Args {
    std::string model, output, structure, format, cache = "256M";
    std::vector<double> percents;
    std::vector<long long> budgets;
    double pixel_error = 1;
    int height = 1080;
    bool no_quantize = false, json = false, at_most = false, no_meshopt = false, stored_cuts = false;
    long long tile_triangles = 16384;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("export", "Several levels of a .mco model -> one glTF LOD chain, or a file each");
  cmd->add_option("model", args->model, "Model written by scan2lod build (.mco)")->required();
  cmd->add_option("-o,--output", args->output,
                  "Output: .glb or .gltf (one file, MSFT_lod chain), or a mesh name whose folder and stem name "
                  "one file per level (bunny.ply -> bunny_LOD0.ply, ...)")
      ->required();
  cmd->add_option("--structure", args->structure, "clusters or octree (default: clusters when the model has them)")
      ->transform(CLI::IsMember(structure_names(), CLI::ignore_case));
  CLI::Option* levels = cmd->add_option("--levels", args->percents,
                                        "Levels as percentages, e.g. 100,25,5,1 (the default); a repeated one is "
                                        "written once")
                            ->delimiter(',');
  CLI::Option* budgets = cmd->add_option("--triangles", args->budgets,
                                         "Levels as triangle budgets, e.g. 200000,50000,10000,2000, each met within "
                                         "10 % (as extract --triangles)")
                             ->delimiter(',');
  cmd->add_flag("--at-most", args->at_most, "With --triangles: no level over its budget")->needs(budgets);
  cmd->add_flag("--stored-cuts", args->stored_cuts,
                "Clusters: each level the stored cut its count gets, not refined to the count (as extract "
                "--stored-cut)");
  levels->excludes(budgets);
  cmd->add_option("--format", args->format,
                  "glb, gltf, ply, obj, off, stl or vtp (default: -o's extension), or 3dtiles (-o names a folder: "
                  "a 3D Tiles 1.1 tileset of the cluster hierarchy, and index.html to view it; see scan2lod serve)")
      ->transform(CLI::IsMember({"glb", "gltf", "ply", "obj", "off", "stl", "vtp", "3dtiles"}, CLI::ignore_case));
  cmd->add_flag("--no-quantize", args->no_quantize, "glTF and 3dtiles: 32-bit float positions and normals");
  const std::vector<CLI::Option*> tileset_flags = {
      cmd->add_option("--tile-triangles", args->tile_triangles,
                      "3dtiles only: most triangles a tile holds (the root holds the coarsest cut)")
          ->default_val(16384),
      cmd->add_flag("--no-meshopt", args->no_meshopt, "3dtiles only: no EXT_meshopt_compression"),
      cmd->add_option("--cache", args->cache,
                      "3dtiles only: pages of the model held in memory at most (default 256M), when the file has "
                      "pages (format 4.6); older files are read whole")};
  // Only glTF stores screen coverage: with a mesh format they would change nothing.
  const std::vector<CLI::Option*> coverage_flags = {
      cmd->add_option("--pixel-error", args->pixel_error,
                      "glTF only: screen coverage, a level is drawn while its error spans at most this many pixels")
          ->default_val(1),
      cmd->add_option("--height", args->height, "glTF only: screen coverage, screen height in pixels")
          ->default_val(1080)};
  cmd->add_flag("--json", args->json, "Print the levels, files, timings and any warnings (\"warnings\") as JSON");
  cmd->callback([args, coverage_flags, tileset_flags, levels, budgets] {
    // --format and --structure come in lower case (CLI11 maps them onto
    // their members).
    if (args->format == "3dtiles") {
      for (const CLI::Option* flag : {levels, budgets})
        if (flag->count())
          throw CLI::ValidationError(flag->get_name(), "does not apply to --format 3dtiles: a tileset holds every "
                                                       "level, from the coarsest cut at its root to full detail");
      for (const CLI::Option* flag : coverage_flags)
        if (flag->count())
          throw CLI::ValidationError(flag->get_name(), "does not apply to --format 3dtiles: the viewer refines "
                                                       "by each tile's geometricError");
      const double cache = parse_bytes(args->cache);
      if (!(cache > 0)) throw CLI::ValidationError("--cache", size_problem(args->cache));
      export_tileset({args->model, args->output, args->structure, args->tile_triangles, args->no_quantize,
                      args->no_meshopt, args->json, std::uint64_t(cache)});
      return;
    }
    for (const CLI::Option* flag : tileset_flags)
      if (flag->count())
        throw CLI::ValidationError(flag->get_name(), "applies to --format 3dtiles only");
    Warnings warnings(args->json);
    const bool default_levels = args->percents.empty() && args->budgets.empty();
    if (default_levels) args->percents = {100, 25, 5, 1};
    args->percents = without_repeats(args->percents, "--levels", warnings);
    args->budgets = without_repeats(args->budgets, "--triangles", warnings);
    const std::vector<LevelRequest> requests = requests_from(args->percents, args->budgets, args->at_most, args->stored_cuts);
    if (!(args->pixel_error > 0) || args->height < 1)
      throw InputError("", "--pixel-error must be > 0 and --height >= 1");
    std::string format = args->format;
    if (format.empty()) format = extension_of(args->output);  // lower case too
    if (format.empty())
      throw InputError(args->output, std::string("has no extension to choose a format by: name the output ") +
                                         kExportFormats + ", or give --format");
    const std::vector<std::string> known = {"glb", "gltf", "ply", "obj", "off", "stl", "vtp"};
    if (std::find(known.begin(), known.end(), format) == known.end())
      throw InputError(args->output, "unknown extension '." + format + "': expected " + kExportFormats);
    const bool gltf = format == "glb" || format == "gltf";
    for (const CLI::Option* flag : coverage_flags)
      if (flag->count() && !gltf)
        throw CLI::ValidationError(flag->get_name(), "applies to a glTF output only; a ." + format +
                                                         " file stores no screen coverage, so it would be ignored");
    std::vector<std::string> outputs;
    if (gltf) {
      outputs.push_back(args->output);
      if (extension_of(args->output) != format)
        throw InputError(args->output, "--format " + format + " needs an output ending in ." + format);
    } else {
      for (std::size_t i = 0; i < requests.size(); ++i) outputs.push_back(level_path(args->output, format, i));
    }
    for (const std::string& out : outputs) {
      check_mesh_output(out);
      refuse_overwriting_inputs(out, {args->model});
    }

    auto start = std::chrono::steady_clock::now();
    const LodModel model = load_model(args->model);
    const double load_seconds = seconds_since(start);
    for (const std::string& out : outputs) check_mesh_output(out, model.origin, model_bounds(model));
    start = std::chrono::steady_clock::now();
    const LodStructure structure = structure_named(model, args->structure, args->model);
    ChainOptions options;
    options.pixel_error = args->pixel_error;
    options.screen_height = args->height;
    const LevelChain chain = extract_chain(model, structure, requests, args->model, options);
    const double extract_seconds = seconds_since(start);
    for (const ChainLevel& l : chain.levels)
      if (!l.shortfall.empty()) warnings(l.shortfall);
    // The chain is finest first; more percent never gives fewer triangles, so
    // the percentages sorted down name its levels in turn.
    std::vector<double> percents = args->percents;
    std::sort(percents.begin(), percents.end(), std::greater<double>());
    const std::string asker = default_levels ? "the default --levels" : "--levels";
    for (std::size_t i = 0; i < percents.size() && i < chain.levels.size(); ++i)
      if (const std::string shortfall = percent_shortfall(model, structure, asker, percents[i], chain.levels[i].cut);
          !shortfall.empty())
        warnings(shortfall);

    start = std::chrono::steady_clock::now();
    if (gltf) {
      std::vector<GltfLevel> levels;
      for (const ChainLevel& l : chain.levels) levels.push_back({&l.cut.triangles, l.name, l.screen_coverage});
      GltfOptions g;
      g.quantize = !args->no_quantize;
      g.generator = std::string("scan2lod ") + SCAN2LOD_VERSION;
      g.origin = model.origin;  // back in the inputs' frame (georeferenced inputs)
      write_gltf_chain(args->output, chain.vertices, levels, g);
    } else {
      MeshWriteOptions write;
      write.origin = model.origin;
      for (std::size_t i = 0; i < chain.levels.size(); ++i) write_mesh(outputs[i], level_mesh(chain, i), write);
    }
    const double write_seconds = seconds_since(start);

    nlohmann::ordered_json j = {{"structure", structure_name(structure)}, {"format", format}};
    j["levels"] = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < chain.levels.size(); ++i) {
      const ChainLevel& l = chain.levels[i];
      nlohmann::ordered_json level = {{"name", l.name},
                                      {"triangles", l.cut.triangles.size()},
                                      {"percent", l.cut.percent},
                                      {"error", l.error},
                                      {"screen_coverage", l.screen_coverage}};
      level["file"] = gltf ? args->output : outputs[i];
      j["levels"].push_back(level);
    }
    std::uintmax_t bytes = 0;
    for (const std::string& out : outputs) {
      std::error_code ec;
      const std::uintmax_t size = fs::file_size(out, ec);
      if (!ec) bytes += size;
    }
    j["vertices"] = chain.vertices.positions.size();
    j["bytes"] = bytes;
    j["seconds"] = {{"load", load_seconds}, {"extract", extract_seconds}, {"write", write_seconds}};
    if (args->json) {
      if (!warnings.kept().empty()) j["warnings"] = warnings.kept();
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    for (const ChainLevel& l : chain.levels)
      say("%s: %zu triangles (%.1f %%), error %.3g, drawn from %.3g of the screen\n", l.name.c_str(),
          l.cut.triangles.size(), l.cut.percent, l.error, l.screen_coverage);
    std::string written;
    for (const std::string& out : outputs) written += (written.empty() ? "" : ", ") + out;
    say("%zu levels of the %s, %zu vertices, %.1f MB; load %.2f s, extract %.3f s, write %.2f s -> %s\n",
        chain.levels.size(), structure_name(structure), chain.vertices.positions.size(), double(bytes) / 1e6,
        load_seconds, extract_seconds, write_seconds, written.c_str());
  });
}

}  // namespace scan2lod::cli
