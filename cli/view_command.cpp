// scan2lod view: the interactive VTK viewer on a .mco model, a mesh or a scan
// set (visualize/viewer.h). --script drives it without a human: the same
// slider moves and key presses, then it exits.
#include <scan2lod/cli/byte_size.h>
#include <scan2lod/cli/commands.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/visualize/levels.h>
#include <scan2lod/visualize/montage.h>
#include <scan2lod/visualize/png_output.h>
#include <scan2lod/visualize/viewer.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

namespace scan2lod::cli {

void add_view_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> inputs;
    std::string size = "1200x800", screenshot = "scan2lod_view.png", script, structure, cache;
    double percent = 100, compare = 20;
    bool offscreen = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("view", "Interactive viewer: a .mco model's levels, a mesh, or a scan set");
  cmd->add_option("inputs", args->inputs,
                  "A .mco model, a mesh (.ply .obj .off .stl .vtp), or a scan set (.conf, range-grid PLYs, PCDs)")
      ->required();
  cmd->add_option("--percent", args->percent,
                  "First level shown (% of the LOD array for the octree, of the full-detail triangles for the "
                  "clusters)")
      ->capture_default_str();
  cmd->add_option("--cache", args->cache,
                  "A model with pages is read page by page, holding at most this much (e.g. 256M), starting on "
                  "the camera cut; without it the model is read whole")
      ->check(size_problem);
  cmd->add_option("--structure", args->structure,
                  "A model's LOD structure to show: clusters (keys c, f, l: camera cut, freeze, DAG levels) or "
                  "octree (key o: cells); default: clusters when the model has them")
      ->check(CLI::IsMember(structure_names()));
  cmd->add_option("--compare", args->compare, "Level of the split view's right half (key v)")->capture_default_str();
  cmd->add_option("--size", args->size, "Window pixels, WIDTHxHEIGHT")->capture_default_str();
  CLI::Option* screenshot =
      cmd->add_option("--screenshot", args->screenshot, "Where key s saves (NAME_2.png, ... once it exists)")
          ->capture_default_str();
  cmd->add_option("--script", args->script,
                  "Run commands from FILE instead of waiting for a user, print the state after each, and exit "
                  "(percent P | triangles T | slider V | key KEY | orbit DEGREES | zoom FACTOR | screenshot PATH | print)");
  cmd->add_flag("--offscreen", args->offscreen, "Render without showing a window (with --script; implied by it)");
  cmd->callback([args, screenshot] {
    ViewerOptions options;
    parse_size(args->size, "--size", &options.width, &options.height);
    if (!(args->percent >= 0 && args->percent <= 100))
      throw InputError("", "--percent must be between 0 and 100, got " + std::to_string(args->percent));
    if (!(args->compare >= 0 && args->compare <= 100))
      throw InputError("", "--compare must be between 0 and 100, got " + std::to_string(args->compare));
    if (args->offscreen && args->script.empty())
      throw InputError("", "--offscreen needs --script: an off-screen viewer with nobody to drive it would never "
                           "end (for pictures without a script, use scan2lod render)");
    check_png_output(args->screenshot);
    // Named on the command line, it must be writable; the default is only
    // written if the user asks (key s) and must not stop a viewer started in
    // a read-only folder. An existing one is not replaced (key s picks NAME_2),
    // so then only its folder matters.
    if (screenshot->count() > 0) {
      const std::filesystem::path shot(args->screenshot);
      if (!std::filesystem::exists(shot)) check_output_path(args->screenshot);
      else check_output_folder(shot.has_parent_path() ? shot.parent_path().string() : ".");
    }
    std::ifstream script;
    if (!args->script.empty()) {
      script.open(args->script);
      if (!script) throw InputError(args->script, "cannot open the script");
    }
    options.percent = args->percent;
    options.compare_percent = args->compare;
    options.screenshot = args->screenshot;
    options.offscreen = args->offscreen || !args->script.empty();
    // File errors first, then the display.
    const bool whole = args->cache.empty() || args->structure == "octree";
    ViewerInput input = load_viewer_input(args->inputs, whole ? 0 : std::uint64_t(parse_bytes(args->cache)));
    if (!args->cache.empty() && input.model && !input.paged && args->structure != "octree")
      std::fprintf(stderr, "scan2lod: %s has no pages (written before format 4.6): read whole\n", input.source.c_str());
    if (input.model) options.structure = structure_named(*input.model, args->structure, input.source);
    else if (!args->structure.empty())
      throw InputError(input.source, "--structure applies to a .mco model, not to a mesh or a scan set");
    require_display("view");
    Viewer viewer(std::move(input), options);
    if (!args->script.empty()) {
      std::cout << describe(viewer.state()) << '\n';
      viewer.run_script(script, args->script, std::cout);
      return;
    }
    viewer.start();
  });
}

}  // namespace scan2lod::cli
