#include "cli/commands.h"
#include "core/progress.h"

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  CLI::App app{"scan2lod: range scans to continuous level-of-detail models"};
  app.require_subcommand(1);
  app.fallthrough();
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "No progress output");
  app.parse_complete_callback([&] { scan2lod::Progress::set_quiet(quiet); });
  scan2lod::cli::add_reconstruct_command(app);
  scan2lod::cli::add_scan_command(app);
  scan2lod::cli::add_compare_command(app);
  scan2lod::cli::add_convert_command(app);
  scan2lod::cli::add_build_command(app);
  scan2lod::cli::add_extract_command(app);
  scan2lod::cli::add_info_command(app);
  scan2lod::cli::add_render_command(app);
  scan2lod::cli::add_plot_command(app);
  scan2lod::cli::add_view_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scan2lod: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
