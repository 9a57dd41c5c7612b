// scan2lod: the commands that only read models (info, extract, export, serve) run
// here, in a program that maps no PCL, VTK or Open3D library (about 170
// shared objects, most of a short command's start); every other command, and
// any that names a .vtp file, runs in scan2lod-full (cli/full_program.h).
#include <scan2lod/cli/app.h>
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/full_program.h>

int main(int argc, char** argv) {
  using namespace scan2lod::cli;
  if (needs_full_program(argc, argv)) return run_full_program(argc, argv);
  return run_app(argc, argv, [](CLI::App& app) {
    add_extract_command(app);
    add_export_command(app);
    add_info_command(app);
    add_serve_command(app);
  });
}
