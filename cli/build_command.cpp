// scan2lod build: inputs -> reconstruction -> marching-cube octree -> LOD
// array -> .mco model (seed 003 §5-6), in one run.
#include "acquisition/load_inputs.h"
#include "cli/commands.h"
#include "cli/reconstruct_flags.h"
#include "lod/lod_array.h"
#include "lod/mc_octree.h"
#include "lod/model_file.h"

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
    bool verbose = false;
    LodMetric metric = LodMetric::kDeviation;
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
                  "area (the seed's area difference)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, LodMetric>{{"deviation", LodMetric::kDeviation}, {"area", LodMetric::kAreaDifference}},
          CLI::ignore_case))
      ->default_str("deviation");
  cmd->add_flag("-v,--verbose", args->verbose, "Print the time of each reconstruction stage");
  cmd->callback([args] {
    using clock = std::chrono::steady_clock;
    auto since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
    const auto start = clock::now();
    const ReconstructOptions& options = args->flags.resolve();
    check_model_output(args->output);
    AcquisitionOptions acquisition;
    acquisition.threads = options.threads;
    const OrientedPoints points = load_oriented_points(args->inputs, acquisition);
    const double read_seconds = since(start);

    auto stage = clock::now();
    Reconstruction r = reconstruct(points, options);
    require_surface(args->inputs, r, options.resolution);
    const double reconstruct_seconds = since(stage);

    stage = clock::now();
    LodModel model;
    OctreeOptions octree;
    octree.metric = args->metric;
    model.tree = build_mc_octree(r, octree);
    model.lod = number_nodes(model.tree);
    const double octree_seconds = since(stage);

    stage = clock::now();
    save_model(args->output, model);
    const double write_seconds = since(stage);

    if (args->verbose) {
      const ReconstructStats& s = r.stats;
      std::printf("reconstruct: kd-tree %.3f s, signed distances %.3f s, marching cubes %.3f s, "
                  "pieces and holes %.3f s, attributes %.3f s\n",
                  s.seconds_index, s.seconds_distances, s.seconds_emit, s.seconds_cleanup, s.seconds_attributes);
    }
    std::size_t leaves = 0;
    for (std::size_t n = 0; n < model.tree.size(); ++n) leaves += model.tree.is_leaf(n);
    std::printf("%zu points, %zu leaves, %zu nodes, %zu expansions, %lld triangles at 100%%, %.2f s "
                "(read %.2f s, reconstruct %.2f s, octree %.2f s, write %.2f s) -> %s\n",
                r.stats.points, leaves, model.tree.size(), model.lod.full(),
                static_cast<long long>(model.lod.accumulated.back()), since(start), read_seconds,
                reconstruct_seconds, octree_seconds, write_seconds, args->output.c_str());
  });
}

}  // namespace scan2lod::cli
