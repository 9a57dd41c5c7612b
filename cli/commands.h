// The command line is a thin layer: each subcommand parses flags into a stage's
// options struct and calls the library.
#pragma once

#include <CLI/CLI.hpp>

namespace scan2lod::cli {

void add_reconstruct_command(CLI::App& app);
void add_scan_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_convert_command(CLI::App& app);
void add_build_command(CLI::App& app);    // lod/: scans -> .mco model
void add_extract_command(CLI::App& app);  // .mco -> mesh at one level of detail
void add_export_command(CLI::App& app);   // .mco -> several levels: a glTF LOD chain or a file each
void add_info_command(CLI::App& app);     // .mco -> levels and sizes
void add_render_command(CLI::App& app);   // visualize/: .mco -> PNG montage of levels
void add_plot_command(CLI::App& app);     // visualize/: .mco -> LOD graphs (PNG)
void add_view_command(CLI::App& app);     // visualize/: the interactive viewer
void add_serve_command(CLI::App& app);    // delivery/: a tileset folder over HTTP

}  // namespace scan2lod::cli
