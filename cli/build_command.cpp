// scan2lod build: inputs -> reconstruction -> LOD structures -> .mco model,
// in one run: the prioritized marching-cube octree (Lee 2007) and the cluster
// hierarchy (Cignoni et al. 2005), or either alone.
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/outputs.h>
#include <scan2lod/cli/reconstruct_flags.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/distributed/work_sharing.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/pipeline/build_model.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>

namespace scan2lod::cli {
namespace {

// --structure: one of the structures, or "both".
std::vector<std::string> with_both(std::vector<std::string> names) {
  names.push_back("both");
  return names;
}

struct Args {
  std::vector<std::string> inputs;
  std::string output;
  ReconstructFlags flags;
  bool verbose = false, json = false;
  LodMetric metric = LodMetric::kDeviation;
  std::string structure = "both";
  std::int64_t cluster_block = 0;
};

void build(Args* args, WorkSharing* job);

BuildOptions options_of(Args& args, WorkSharing* job) {
  BuildOptions options = args.flags.build_options(args.output);
  options.octree = args.structure != "clusters";
  options.clusters = args.structure != "octree";
  options.cluster_block = args.cluster_block;
  options.metric = args.metric;
  options.sharing = job;
  return options;
}

// Under mpirun every rank runs this command: each reads its share of the
// inputs, rank 0 builds and writes the model, the others take their share of
// the bricks and write nothing else. An error on any rank ends them all.
void build_in_job(Args* args) {
  const std::unique_ptr<WorkSharing> job = join_job();
  const std::string rank =
      job->ranks() > 1 ? "rank " + std::to_string(job->rank()) + " of " + std::to_string(job->ranks()) : "";
  if (job->rank() != 0) {
    set_quiet(true);  // rank 0 speaks for the job; errors still print
    set_progress_sink({});
  } else if (launched_by_mpi() && !quiet()) {
    install_terminal_progress(true);
  }
  try {
    build(args, job.get());
  } catch (...) {
    if (job->ranks() == 1) throw;
    job->abort(print_error(rank));
  }
}

}  // namespace

void add_build_command(CLI::App& app) {
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "build", "Range scans, point clouds or a mesh -> LOD model (.mco): marching-cube octree and LOD array");
  cmd->add_option("inputs", args->inputs,
                  kInputsHelp)
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
      ->check(CLI::IsMember(with_both(structure_names()), CLI::ignore_case))
      ->default_str("both");
  cmd->add_option("--cluster-block", args->cluster_block,
                  "Triangles per block of the cluster hierarchy; with it the hierarchy is always built in blocks "
                  "(default: 131072 above 1048576 triangles, the same at any --memory that holds them)")
      ->check(CLI::Range(std::int64_t(1024), std::int64_t(1) << 40));
  cmd->add_flag("-v,--verbose", args->verbose, "Print the time of each reconstruction stage");
  cmd->add_flag("--json", args->json, "Print the counts and stage times as JSON");
  cmd->callback([args] { build_in_job(args.get()); });
}

namespace {

void build(Args* args, WorkSharing* job) {
  if (job->rank() != 0) return serve_build(args->inputs, options_of(*args, job));
  using clock = std::chrono::steady_clock;
  auto since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  const auto start = clock::now();
  check_model_output(args->output);
  check_output_path(args->output);  // writable, before minutes of work
  refuse_overwriting_inputs(args->output, args->inputs);
  const BuildOptions options = options_of(*args, job);
  BuildReport report;
  LodModel model = build_model(args->inputs, options, &report);
  for (const std::string& warning : report.warnings) warn(warning);
  refuse_overwriting_inputs(args->output, report.acquisition.files);

  auto stage = clock::now();
  save_model(args->output, model);
  const double write_seconds = since(stage);
  args->flags.finished(report, options);
  const std::size_t points = report.points;
  const double read_seconds = report.seconds_read, reconstruct_seconds = report.seconds_reconstruct,
               octree_seconds = report.seconds_octree, cluster_seconds = report.seconds_clusters;
  if (args->json) {
    nlohmann::ordered_json j = {{"points", points}, {"vertices", model.vertices.size()}};
    if (model.has(LodStructure::kOctree)) {
      const OctreeSummary o = describe_octree(model);
      j["octree"] = {{"nodes", o.nodes}, {"expansions", o.expansions}, {"full_triangles", o.full_triangles}};
    }
    if (model.has(LodStructure::kClusters)) {
      const ClusterSummary c = describe_clusters(model);
      j["clusters"] = {{"clusters", c.clusters}, {"levels", c.levels}, {"full_triangles", c.full_triangles},
                       {"coarsest_triangles", c.coarsest_triangles}};
    }
    if (report.in_bricks)
      j["bricks"] = {{"brick_cubes", report.plan.brick_cubes}, {"bricks", report.bricks.bricks},
                     {"runs", report.bricks.brick_runs}, {"resumed", report.bricks.bricks_resumed},
                     {"follow_passes", report.bricks.follow_passes}, {"halo", report.plan.halo},
                     {"widest_halo", report.bricks.widest_halo}};
    if (report.cluster_block > 0) j["cluster_block"] = report.cluster_block;
    if (report.cluster_lanes > 0) j["cluster_lanes"] = report.cluster_lanes;
    if (report.cluster_blocks.blocks > 0)
      j["cluster_blocks"] = {{"made", report.cluster_blocks.blocks}, {"here", report.cluster_blocks.blocks_here},
                             {"exchanged_mib", report.cluster_blocks.bytes_exchanged / double(1 << 20)}};
    const double mib = 1 << 20;
    j["memory_mib"] = {{"budget", report.budget_bytes / mib},
                       {"estimated", {{"in_core_reconstruction", report.estimated_bytes / mib},
                                      {"brick", report.plan.brick_bytes / mib},
                                      {"weld", report.plan.weld_bytes / mib},
                                      {"clusters", report.estimated_cluster_bytes / mib}}},
                       {"peak_after", {{"reconstruct", report.peak_bytes_reconstruct / mib},
                                       {"octree", report.peak_bytes_octree / mib},
                                       {"clusters", report.peak_bytes_clusters / mib}}}};
    j["output"] = args->output;
    j["seconds"] = {{"total", since(start)}, {"read", read_seconds}, {"reconstruct", reconstruct_seconds},
                    {"octree", octree_seconds}, {"clusters", cluster_seconds}, {"write", write_seconds}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  if (args->verbose) {
    const ReconstructStats& s = report.reconstruct;
    say("reconstruct: kd-tree %.3f s, signed distances %.3f s, marching cubes %.3f s, "
                "pieces and holes %.3f s, attributes %.3f s\n",
                s.seconds_index, s.seconds_distances, s.seconds_emit, s.seconds_cleanup, s.seconds_attributes);
    if (report.in_bricks)
      say("bricks of %d cubes (halo %.3g): %zu bricks, %zu runs, %zu resumed, %zu passes\n", report.plan.brick_cubes,
          report.plan.halo, report.bricks.bricks, report.bricks.brick_runs, report.bricks.bricks_resumed,
          report.bricks.follow_passes);
  }
  say("%zu points, %zu vertices", points, model.vertices.size());
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
}

}  // namespace

}  // namespace scan2lod::cli
