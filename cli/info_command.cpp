// scan2lod info: what a .mco model holds, and the size of each structure's
// levels at the usual percentages (Lee 2007, Figs. 6.3-6.4).
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>

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

    if (model.has(LodStructure::kOctree)) {
      const OctreeSummary o = describe_octree(model);
      const auto lods = summarize_levels(model, LodStructure::kOctree, percents);
      if (args->json) {
        nlohmann::ordered_json levels = nlohmann::ordered_json::array();
        for (const LevelSummary& l : lods)
          levels.push_back({{"percent", l.percent}, {"priority", l.priority}, {"triangles", l.triangles},
                            {"vertices", l.vertices}});
        j["octree"] = {{"resolution", o.resolution},   {"depth", o.depth},   {"nodes", o.nodes},
                       {"nodes_per_level", o.nodes_per_level}, {"leaves", o.leaves}, {"expansions", o.expansions},
                       {"pinned", o.pinned},           {"offered_levels", o.offered_levels},
                       {"coarsest_offered_triangles", o.coarsest_triangles}, {"levels_of_detail", levels}};
        // Kept at the top level too, as before the cluster hierarchy.
        for (const char* key : {"resolution", "depth", "nodes", "nodes_per_level", "leaves", "expansions", "pinned",
                                "levels_of_detail"})
          j[key] = j["octree"][key];
      } else {
        say("\noctree: resolution %d (depth %d), cube size %.6g, origin (%.6g, %.6g, %.6g)\n", o.resolution,
                    o.depth, o.cube_size, o.origin.x(), o.origin.y(), o.origin.z());
        say("%zu nodes, %zu leaves, %zu expansions; nodes per level:", o.nodes, o.leaves, o.expansions);
        for (std::size_t c : o.nodes_per_level) say(" %zu", c);
        if (o.pinned)
          say("\nthe first %zu expansions (%lld triangles) keep the rim at full detail: no level is offered "
                      "inside them",
                      o.pinned, static_cast<long long>(o.pinned_triangles));
        say("\n%zu levels offered, from %lld triangles to %lld", o.offered_levels,
            static_cast<long long>(o.coarsest_triangles), static_cast<long long>(o.full_triangles));
        say("\n\n%6s %10s %10s %10s\n", "LOD %", "priority", "triangles", "vertices");
        for (const LevelSummary& l : lods)
          say("%6g %10zu %10zu %10zu\n", l.percent, l.priority, l.triangles, l.vertices);
      }
    }
    if (model.has(LodStructure::kClusters)) {
      const ClusterSummary c = describe_clusters(model);
      const auto lods = summarize_levels(model, LodStructure::kClusters, percents);
      if (args->json) {
        nlohmann::ordered_json levels = nlohmann::ordered_json::array();
        for (const LevelSummary& l : lods)
          levels.push_back({{"percent", l.percent}, {"error", l.error}, {"clusters", l.clusters},
                            {"triangles", l.triangles}, {"vertices", l.vertices}});
        j["clusters"] = {{"clusters", c.clusters},
                         {"groups", c.groups},
                         {"levels", c.levels},
                         {"full_triangles", c.full_triangles},
                         {"stored_triangles", c.stored_triangles},
                         {"coarsest_triangles", c.coarsest_triangles},
                         {"levels_of_detail", levels}};
      } else {
        say("\nclusters: %zu clusters in %zu groups over %d levels; %zu triangles stored (%.2fx the full "
                    "mesh's %lld); the coarsest cut has %lld\n",
                    c.clusters, c.groups, c.levels, c.stored_triangles,
                    c.full_triangles ? double(c.stored_triangles) / double(c.full_triangles) : 0.0,
                    static_cast<long long>(c.full_triangles), static_cast<long long>(c.coarsest_triangles));
        say("\n%6s %10s %10s %10s %10s\n", "LOD %", "error", "clusters", "triangles", "vertices");
        for (const LevelSummary& l : lods)
          say("%6g %10.3g %10zu %10zu %10zu\n", l.percent, l.error, l.clusters, l.triangles, l.vertices);
      }
    }
    if (args->json) std::printf("%s\n", j.dump(2).c_str());
  });
}

}  // namespace scan2lod::cli
