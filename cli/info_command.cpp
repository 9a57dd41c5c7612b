// scan2lod info: what a .mco model holds, and the size of each structure's
// levels at the usual percentages (Lee 2007, Figs. 6.3-6.4).
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/structure.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace scan2lod::cli {

void add_info_command(CLI::App& app) {
  struct Args {
    std::string model;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("info", "Structures, node and cluster counts and LOD sizes of a .mco model");
  cmd->add_option("model", args->model, "Model written by scan2lod build (.mco)")->required();
  cmd->add_flag("--json", args->json, "Print one JSON object (keys in README.md, \"LOD models\")");
  cmd->callback([args] {
    const auto start = std::chrono::steady_clock::now();
    const LodModel model = load_model(args->model);
    const double load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::vector<double> percents = {100, 80, 60, 40, 20, 10, 5, 1};
    nlohmann::ordered_json j = {{"vertices", model.vertices.size()}};
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(args->model, ec);
    if (!args->json)
      say("%s: %.1f MB, loaded in %.3f s, %zu vertices\n", args->model.c_str(), ec ? 0.0 : double(bytes) / 1e6,
                  load_seconds, model.vertices.size());
    // A georeferenced model's frame: positions are relative to it, and every
    // writer adds it back.
    if (model.origin != Vec3d::Zero()) {
      if (args->json) j["origin"] = {model.origin.x(), model.origin.y(), model.origin.z()};
      else say("origin (%.17g, %.17g, %.17g): positions are relative to it; levels are written in its frame\n",
               model.origin.x(), model.origin.y(), model.origin.z());
    }

    // Each structure the model holds, as the file lays them out.
    for (const StructureKind* kind : structures_in_file_order()) {
      if (!kind->present(model)) continue;
      const StructureInfo info = kind->info(model, percents);
      if (args->json) {
        j[kind->name] = info.json;
        for (const std::string& key : info.top_level_keys) j[key] = info.json[key];
      } else {
        say("%s", info.text.c_str());
      }
    }
    if (args->json) std::printf("%s\n", j.dump(2).c_str());
  });
}

}  // namespace scan2lod::cli
