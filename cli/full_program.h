// `scan2lod` runs the commands that need PCL, VTK or Open3D in the program
// that has them, scan2lod-full, beside it in the build folder and in
// libexec/scan2lod once installed, as git runs its dashed commands.
#pragma once

namespace scan2lod::cli {

// Whether the command line needs scan2lod-full: no command (the help of all),
// a command other than info, extract, export and serve, or a .vtp file (VTK's).
bool needs_full_program(int argc, char** argv);

// Replaces this process with scan2lod-full and the same arguments (the same
// process: an MPI launcher's rank stays its rank). Returns only when it cannot
// be run, with the exit code of the error it printed.
int run_full_program(int argc, char** argv);

}  // namespace scan2lod::cli
