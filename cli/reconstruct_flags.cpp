#include <scan2lod/cli/reconstruct_flags.h>

#include <scan2lod/cli/byte_size.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/cli/usage.h>
#include <scan2lod/core/error.h>

#include <cstdio>
#include <filesystem>

namespace scan2lod::cli {

const ReconstructOptions& ReconstructFlags::resolve() {
  options.distance.method = parse_distance_method(method);
  options.threads = usable_threads(options.threads);
  acquisition.threads = options.threads;
  return options;
}

BuildOptions ReconstructFlags::build_options(const std::string& output) {
  BuildOptions b;
  b.reconstruct = resolve();
  b.acquisition = acquisition;
  b.memory_bytes = memory.empty() ? 0 : parse_bytes(memory);
  b.work_dir = work_dir.empty() ? output + ".work" : work_dir;
  b.brick_cubes = brick_cubes;
  if (brick_cubes > 0) b.strategy = BuildStrategy::kBricks;
  return b;
}

void ReconstructFlags::finished(const BuildReport& report, const BuildOptions& options) const {
  if ((!report.in_bricks && report.cluster_block == 0) || !work_dir.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(options.work_dir, ec);
}

void add_reconstruct_flags(CLI::App* cmd, ReconstructFlags* flags) {
  ReconstructOptions& o = flags->options;
  cmd->add_option("-r,--resolution", o.resolution, "Cubes per side (a power of two, 16 or more)")->capture_default_str();
  cmd->add_option("--margin", o.margin, "Cubes grown around point-holding cubes before surface following")
      ->capture_default_str();
  cmd->add_option("--distance", flags->method, "Signed distance: planes, hoppe or closest (the closest point's, as Lee 2007; also spelt seed)")->capture_default_str();
  cmd->add_option("--neighbours", o.distance.neighbours, "Points averaged by the planes distance")
      ->capture_default_str();
  cmd->add_option("--max-distance", o.distance.max_distance,
                  "Corners farther than this many cube sizes (or sample spacings) from data stay undefined")
      ->capture_default_str();
  cmd->add_option("--reach", o.reach,
                  "Cubes reached by following the surface are kept within this many cube sizes (or sample spacings) of data")
      ->capture_default_str();
  cmd->add_option("--min-piece", o.min_piece, "Remove pieces with less than this fraction of the triangles (0: keep all)")
      ->capture_default_str();
  cmd->add_option("--max-hole", o.max_hole,
                  "Close holes whose rim has at most this many edges per cube of resolution (0: none)")
      ->capture_default_str();
  cmd->add_option("--hole-rounds", o.hole_rounds, "Rings of cubes a small hole is closed by from each side, at most")
      ->capture_default_str();
  cmd->add_flag("--unregistered", flags->acquisition.unregistered,
                "Range-grid PLYs given without their .conf already share one frame: merge them as they are");
  cmd->add_option("--memory", flags->memory,
                  "Memory the work may take, e.g. 400M or 4G (default: what the machine has available, less a "
                  "tenth). A reconstruction whose estimate exceeds it runs brick by brick, with the same surface")
      ->check(size_problem);
  cmd->add_option("--work-dir", flags->work_dir,
                  "Folder for the bricks; run again with the same folder, a killed build resumes from its finished "
                  "bricks (default: OUTPUT.work, removed when the output is written)");
  cmd->add_option("--brick-cubes", flags->brick_cubes,
                  "Cubes per brick side, a power of two of 16 or more; with it the work always runs in bricks "
                  "(default: from --memory)");
  add_threads_option(cmd, &o.threads);
}

void require_surface(const std::vector<std::string>& inputs, const Reconstruction& r, int resolution) {
  for (const std::string& warning : r.warnings) warn(warning);
  if (!r.mesh.triangles.empty()) return;
  std::string names;
  for (const std::string& input : inputs) names += (names.empty() ? "" : ", ") + input;
  throw InputError(names, no_surface_message(r, resolution, "--resolution"));
}

}  // namespace scan2lod::cli
