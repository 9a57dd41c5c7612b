#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/outputs.h>
#include <scan2lod/cli/reconstruct_flags.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <memory>

namespace scan2lod::cli {

void add_reconstruct_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> inputs;
    std::string output;
    ReconstructFlags flags;
    bool verbose = false, json = false, no_quantize = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "reconstruct", "Range scans, point clouds or a mesh -> marching-cubes mesh");
  cmd->add_option("inputs", args->inputs,
                  kInputsHelp)
      ->required();
  cmd->add_option("-o,--output", args->output, "Output mesh (.ply .obj .stl .off .vtp .glb .gltf)")->required();
  cmd->add_flag("--no-quantize", args->no_quantize, "glTF: 32-bit float positions and normals");
  cmd->add_flag("--json", args->json, "Print the counts and stage times as JSON");
  add_reconstruct_flags(cmd, &args->flags);
  cmd->add_flag("-v,--verbose", args->verbose, "Print the time of each stage");
  cmd->callback([args] {
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    const BuildOptions build = args->flags.build_options(args->output);
    const ReconstructOptions& options = build.reconstruct;
    check_mesh_output(args->output);
    refuse_overwriting_inputs(args->output, args->inputs);
    AcquisitionReport report;
    InputPoints points = load_within_budget(args->inputs, build, &report);
    for (const std::string& warning : report.warnings) warn(warning);
    refuse_overwriting_inputs(args->output, report.files);
    // The mesh will lie about the inputs' origin, near their points: can the format hold it there?
    check_mesh_output(args->output, report.origin,
                      points.spool ? points.spool->census().box : bounds(points.points.positions));
    const double read_seconds = std::chrono::duration<double>(clock::now() - start).count();
    BuildOptions only_mesh = build;
    only_mesh.octree = only_mesh.clusters = false;
    BuildReport report_bricks;
    Reconstruction r = reconstruct_within_budget(&points, only_mesh, &report_bricks);
    for (const std::string& warning : report_bricks.warnings) warn(warning);
    require_surface(args->inputs, r, options.resolution);
    const auto write_start = clock::now();
    MeshWriteOptions write;
    write.quantize = !args->no_quantize;
    write.generator = std::string("scan2lod ") + SCAN2LOD_VERSION;
    write.origin = report.origin;  // back in the inputs' frame (georeferenced inputs)
    const std::size_t vertices_written = write_mesh(args->output, r.mesh, write);
    args->flags.finished(report_bricks, build);
    const double write_seconds = std::chrono::duration<double>(clock::now() - write_start).count();
    const double seconds = std::chrono::duration<double>(clock::now() - start).count();
    if (args->json) {
      const ReconstructStats& s = r.stats;
      const nlohmann::ordered_json j = {
          {"points", s.points}, {"cubes_touched", s.cubes_touched}, {"cubes_emitting", s.cubes_emitting},
          {"triangles", r.mesh.triangles.size()}, {"vertices", vertices_written}, {"output", args->output},
          {"seconds", {{"total", seconds}, {"read", read_seconds}, {"kd_tree", s.seconds_index},
                       {"signed_distances", s.seconds_distances}, {"marching_cubes", s.seconds_emit},
                       {"pieces_and_holes", s.seconds_cleanup}, {"attributes", s.seconds_attributes},
                       {"write", write_seconds}}}};
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    if (args->verbose) {
      const ReconstructStats& s = r.stats;
      say("read %.3f s, kd-tree %.3f s, signed distances %.3f s (%zu corners, %zu following rounds), "
                  "marching cubes %.3f s, pieces and holes %.3f s (%zu triangles dropped, %zu cubes closing holes), "
                  "attributes %.3f s, write %.3f s\n",
                  read_seconds, s.seconds_index, s.seconds_distances, s.corners_evaluated, s.following_rounds,
                  s.seconds_emit, s.seconds_cleanup, s.triangles_dropped, s.cubes_hole_closing,
                  s.seconds_attributes,
                  write_seconds);
    }
    say("%zu points, %zu cubes touched, %zu emitting, %zu triangles, %zu vertices, %.2f s -> %s\n",
                r.stats.points, r.stats.cubes_touched, r.stats.cubes_emitting,
                r.mesh.triangles.size(), vertices_written, seconds, args->output.c_str());
  });
}

}  // namespace scan2lod::cli
