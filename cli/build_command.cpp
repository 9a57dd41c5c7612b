// scan2lod build: inputs -> reconstruction -> LOD structures -> .mco model,
// in one run: the prioritized marching-cube octree (Lee 2007) and the cluster
// hierarchy (Cignoni et al. 2005), or either alone.
#include "acquisition/load_inputs.h"
#include "cli/commands.h"
#include "cli/outputs.h"
#include "cli/reconstruct_flags.h"
#include "cli/terminal.h"
#include "io/mesh_file.h"
#include "lod/lod_array.h"
#include "lod/octree_order.h"
#include "lod/mc_octree.h"
#include "lod/model_file.h"

#include "core/progress.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>

namespace scan2lod::cli {

void add_build_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> inputs;
    std::string output;
    ReconstructFlags flags;
    bool verbose = false, json = false;
    LodMetric metric = LodMetric::kDeviation;
    std::string structure = "both";
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "build", "Range scans, organized clouds or a mesh -> LOD model (.mco): marching-cube octree and LOD array");
  cmd->add_option("inputs", args->inputs,
                  "A .conf, range-grid PLYs, organized PCDs, or a mesh (.ply .obj .off .stl)")
      ->required();
  cmd->add_option("-o,--output", args->output, "Output model (.mco)")->required();
  add_reconstruct_flags(cmd, &args->flags);
  cmd->add_option("--metric", args->metric,
                  "What orders the expansions: deviation (from the leaf surface, per triangle) or "
                  "area (Lee's area difference)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, LodMetric>{{"deviation", LodMetric::kDeviation}, {"area", LodMetric::kAreaDifference}},
          CLI::ignore_case))
      ->default_str("deviation");
  cmd->add_option("--structure", args->structure,
                  "LOD structures to build: clusters (the cluster hierarchy), octree (the marching-cube octree) or "
                  "both. A mesh input's own triangles are the clusters' full detail.")
      ->check(CLI::IsMember({"clusters", "octree", "both"}, CLI::ignore_case))
      ->default_str("both");
  cmd->add_flag("-v,--verbose", args->verbose, "Print the time of each reconstruction stage");
  cmd->add_flag("--json", args->json, "Print the counts and stage times as JSON");
  cmd->callback([args] {
    using clock = std::chrono::steady_clock;
    auto since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
    const auto start = clock::now();
    const ReconstructOptions& options = args->flags.resolve();
    check_model_output(args->output);
    refuse_overwriting_inputs(args->output, args->inputs);
    const AcquisitionOptions& acquisition = args->flags.acquisition;
    const bool want_octree = args->structure != "clusters", want_clusters = args->structure != "octree";
    // A single mesh input keeps its own triangles for the cluster hierarchy.
    AcquisitionReport report;
    const OrientedPoints points = load_oriented_points(args->inputs, acquisition, &report);
    refuse_overwriting_inputs(args->output, report.files);
    const bool mesh_input = report.meshes == 1 && report.files.size() == 1;
    const double read_seconds = since(start);

    auto stage = clock::now();
    Reconstruction r;
    if (want_octree || !mesh_input) {
      r = reconstruct(points, options);
      require_surface(args->inputs, r, options.resolution);
    }
    const double reconstruct_seconds = since(stage);

    stage = clock::now();
    LodModel model;
    if (want_octree) {
      OctreeOptions octree;
      octree.metric = args->metric;
      McOctree tree = build_mc_octree(r, octree);
      LodArray lod = number_nodes(tree);
      model = model_from_octree(std::move(tree), std::move(lod));
    }
    const double octree_seconds = since(stage);

    stage = clock::now();
    if (want_clusters) {
      Progress bar("clusters", 1000);
      ClusterOptions clusters;
      clusters.threads = options.threads;
      clusters.progress = [&bar, done = std::size_t(0)](double share) mutable {
        const std::size_t now = std::size_t(share * 1000);
        if (now > done) bar.advance(now - done), done = now;
      };
      if (mesh_input) add_cluster_hierarchy(&model, read_mesh(args->inputs[0]), false, clusters);
      else add_cluster_hierarchy(&model, r.mesh, want_octree, clusters);
      bar.finish();
    }
    const double cluster_seconds = since(stage);

    stage = clock::now();
    save_model(args->output, model);
    const double write_seconds = since(stage);

    if (args->json) {
      nlohmann::ordered_json j = {{"points", points.size()}, {"vertices", model.vertices.size()}};
      if (model.has(LodStructure::kOctree)) {
        const OctreeSummary o = describe_octree(model);
        j["octree"] = {{"nodes", o.nodes}, {"expansions", o.expansions}, {"full_triangles", o.full_triangles}};
      }
      if (model.has(LodStructure::kClusters)) {
        const ClusterSummary c = describe_clusters(model);
        j["clusters"] = {{"clusters", c.clusters}, {"levels", c.levels}, {"full_triangles", c.full_triangles},
                         {"coarsest_triangles", c.coarsest_triangles}};
      }
      j["output"] = args->output;
      j["seconds"] = {{"total", since(start)}, {"read", read_seconds}, {"reconstruct", reconstruct_seconds},
                      {"octree", octree_seconds}, {"clusters", cluster_seconds}, {"write", write_seconds}};
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    if (args->verbose) {
      const ReconstructStats& s = r.stats;
      say("reconstruct: kd-tree %.3f s, signed distances %.3f s, marching cubes %.3f s, "
                  "pieces and holes %.3f s, attributes %.3f s\n",
                  s.seconds_index, s.seconds_distances, s.seconds_emit, s.seconds_cleanup, s.seconds_attributes);
    }
    say("%zu points, %zu vertices", points.size(), model.vertices.size());
    if (model.has(LodStructure::kOctree)) {
      const OctreeSummary o = describe_octree(model);
      say(", octree: %zu nodes, %zu expansions, %lld triangles at 100%%", o.nodes, o.expansions,
                  static_cast<long long>(o.full_triangles));
    }
    if (model.has(LodStructure::kClusters)) {
      const ClusterSummary c = describe_clusters(model);
      say(", clusters: %zu in %d levels, %lld triangles at 100%%", c.clusters, c.levels,
                  static_cast<long long>(c.full_triangles));
    }
    say(", %.2f s (read %.2f s, reconstruct %.2f s, octree %.2f s, clusters %.2f s, write %.2f s) -> %s\n",
                since(start), read_seconds, reconstruct_seconds, octree_seconds, cluster_seconds, write_seconds,
                args->output.c_str());
  });
}

}  // namespace scan2lod::cli
