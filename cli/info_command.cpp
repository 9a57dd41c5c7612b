// scan2lod info: what a .mco model holds, and the size of its levels of detail
// at the seed's percentages (seed 003 Figs. 6.3-6.4).
#include "cli/commands.h"
#include "lod/extract.h"
#include "lod/model_file.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace scan2lod::cli {
namespace {

struct LevelOfDetail {
  double percent;
  std::size_t priority, triangles, vertices;
};

// Triangles and distinct vertices of the mesh at each percentage.
std::vector<LevelOfDetail> levels_of_detail(const LodModel& model, const std::vector<double>& percents) {
  std::vector<LevelOfDetail> out;
  std::vector<std::uint8_t> scratch, used(model.tree.positions.size(), 0);
  std::vector<Triangle> tris;
  for (double percent : percents) {
    const std::size_t p = priority_for_percent(model.lod, percent);
    extract_lod(model.tree, model.lod, p, &scratch, &tris);
    std::size_t vertices = 0;
    for (const Triangle& t : tris)
      for (std::int32_t v : t)
        if (!used[v]) used[v] = 1, ++vertices;
    for (const Triangle& t : tris)
      for (std::int32_t v : t) used[v] = 0;
    out.push_back({percent, p, tris.size(), vertices});
  }
  return out;
}

}  // namespace

void add_info_command(CLI::App& app) {
  struct Args {
    std::string model;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("info", "Levels, node counts and LOD sizes of a .mco model");
  cmd->add_option("model", args->model, "Model written by scan2lod build (.mco)")->required();
  cmd->add_flag("--json", args->json, "Print one JSON object (keys in README.md, \"LOD models\")");
  cmd->callback([args] {
    const auto start = std::chrono::steady_clock::now();
    const LodModel model = load_model(args->model);
    const double load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const McOctree& t = model.tree;
    std::vector<std::size_t> per_level(std::size_t(t.depth) + 1, 0);
    std::size_t leaves = 0;
    for (std::size_t n = 0; n < t.size(); ++n) {
      ++per_level[t.levels[n]];
      leaves += t.is_leaf(n);
    }
    const auto lods = levels_of_detail(model, {100, 80, 60, 40, 20, 10, 5, 1});

    if (args->json) {
      nlohmann::ordered_json levels = nlohmann::ordered_json::array();
      for (const LevelOfDetail& l : lods)
        levels.push_back(
            {{"percent", l.percent}, {"priority", l.priority}, {"triangles", l.triangles}, {"vertices", l.vertices}});
      const nlohmann::ordered_json j = {{"resolution", t.grid.resolution},
                                {"depth", t.depth},
                                {"nodes", t.size()},
                                {"nodes_per_level", per_level},
                                {"leaves", leaves},
                                {"expansions", model.lod.full()},
                                {"pinned", model.lod.pinned},
                                {"levels_of_detail", levels}};
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(args->model, ec);
    std::printf("%s: %.1f MB, loaded in %.3f s\n", args->model.c_str(), ec ? 0.0 : double(bytes) / 1e6, load_seconds);
    std::printf("resolution %d (depth %d), cube size %.6g, origin (%.6g, %.6g, %.6g)\n", t.grid.resolution, t.depth,
                t.grid.cube_size, t.grid.origin.x(), t.grid.origin.y(), t.grid.origin.z());
    std::printf("%zu nodes, %zu leaves, %zu expansions; nodes per level:", t.size(), leaves, model.lod.full());
    for (std::size_t c : per_level) std::printf(" %zu", c);
    if (model.lod.pinned)
      std::printf("\nthe first %zu expansions (%lld triangles) keep the rim at full detail: no level is offered "
                  "inside them",
                  model.lod.pinned, static_cast<long long>(model.lod.accumulated[model.lod.pinned]));
    std::printf("\n\n%6s %10s %10s %10s\n", "LOD %", "priority", "triangles", "vertices");
    for (const LevelOfDetail& l : lods)
      std::printf("%6g %10zu %10zu %10zu\n", l.percent, l.priority, l.triangles, l.vertices);
  });
}

}  // namespace scan2lod::cli
