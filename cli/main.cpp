// scan2lod-full: every command. `scan2lod` runs this program for the
// commands that need PCL, VTK or Open3D (cli/full_program.h).
#include <scan2lod/cli/app.h>
#include <scan2lod/cli/commands.h>

int main(int argc, char** argv) {
  using namespace scan2lod::cli;
  return run_app(argc, argv, [](CLI::App& app) {
    add_reconstruct_command(app);
    add_scan_command(app);
    add_compare_command(app);
    add_convert_command(app);
    add_build_command(app);
    add_extract_command(app);
    add_export_command(app);
    add_info_command(app);
    add_render_command(app);
    add_plot_command(app);
    add_view_command(app);
    add_serve_command(app);
  });
}
