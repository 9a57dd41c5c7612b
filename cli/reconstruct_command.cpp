#include "acquisition/load_inputs.h"
#include "cli/commands.h"
#include "io/mesh_file.h"
#include "reconstruct/marching_cubes.h"

#include <chrono>
#include <cstdio>
#include <memory>

namespace scan2lod::cli {

void add_reconstruct_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> inputs;
    std::string output;
    std::string method = "planes";
    ReconstructOptions options;
    bool verbose = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "reconstruct", "Range scans, organized clouds or a mesh -> marching-cubes mesh");
  cmd->add_option("inputs", args->inputs,
                  "A .conf, range-grid PLYs, organized PCDs, or a mesh (.ply .obj .off .stl)")
      ->required();
  cmd->add_option("-o,--output", args->output, "Output mesh (.ply .obj .stl .off .vtp)")->required();
  cmd->add_option("-r,--resolution", args->options.resolution, "Cubes per side (power of two)")
      ->capture_default_str();
  cmd->add_option("--margin", args->options.margin,
                  "Cubes grown around point-holding cubes before surface following")
      ->capture_default_str();
  cmd->add_option("--distance", args->method, "Signed distance: planes, hoppe or seed")
      ->capture_default_str();
  cmd->add_option("--neighbours", args->options.distance.neighbours,
                  "Points averaged by the planes distance")
      ->capture_default_str();
  cmd->add_option("--max-distance", args->options.distance.max_distance,
                  "Corners farther than this many cube sizes (or sample spacings) from data stay undefined")
      ->capture_default_str();
  cmd->add_option("--reach", args->options.reach,
                  "Cubes reached by following the surface are kept within this many cube sizes (or sample spacings) of data")
      ->capture_default_str();
  cmd->add_option("--min-piece", args->options.min_piece,
                  "Remove pieces with less than this fraction of the triangles (0: keep all)")
      ->capture_default_str();
  cmd->add_option("--max-hole", args->options.max_hole,
                  "Close holes whose rim has at most this many edges per cube of resolution (0: none)")
      ->capture_default_str();
  cmd->add_option("--hole-rounds", args->options.hole_rounds,
                  "Rings of cubes a small hole is closed by from each side, at most")
      ->capture_default_str();
  cmd->add_option("-j,--threads", args->options.threads, "Threads (0: all cores)")->capture_default_str();
  cmd->add_flag("-v,--verbose", args->verbose, "Print the time of each stage");
  cmd->callback([args] {
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    args->options.distance.method = parse_distance_method(args->method);
    check_mesh_output(args->output);
    AcquisitionOptions acquisition;
    acquisition.threads = args->options.threads;
    OrientedPoints points = load_oriented_points(args->inputs, acquisition);
    const double read_seconds = std::chrono::duration<double>(clock::now() - start).count();
    Reconstruction r = reconstruct(points, args->options);
    const auto write_start = clock::now();
    write_mesh(args->output, r.mesh);
    if (args->verbose) {
      const ReconstructStats& s = r.stats;
      std::printf("read %.3f s, kd-tree %.3f s, signed distances %.3f s (%zu corners, %zu following rounds), "
                  "marching cubes %.3f s, pieces and holes %.3f s (%zu triangles dropped, %zu cubes closing holes), "
                  "attributes %.3f s, write %.3f s\n",
                  read_seconds, s.seconds_index, s.seconds_distances, s.corners_evaluated, s.following_rounds,
                  s.seconds_emit, s.seconds_cleanup, s.triangles_dropped, s.cubes_hole_closing,
                  s.seconds_attributes,
                  std::chrono::duration<double>(clock::now() - write_start).count());
    }
    const double seconds = std::chrono::duration<double>(clock::now() - start).count();
    std::printf("%zu points, %zu cubes touched, %zu emitting, %zu triangles, %zu vertices, %.2f s -> %s\n",
                r.stats.points, r.stats.cubes_touched, r.stats.cubes_emitting,
                r.mesh.triangles.size(), r.mesh.positions.size(), seconds, args->output.c_str());
  });
}

}  // namespace scan2lod::cli
