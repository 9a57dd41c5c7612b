// scan2lod render: levels of a .mco model (of its cluster hierarchy or its
// octree, --structure) off-screen into one PNG montage, the layout of the
// Lee 2007's Fig. 6.3 (wireframe beside shaded, one row per level).
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/visualize/levels.h>
#include <scan2lod/visualize/montage.h>
#include <scan2lod/visualize/png_output.h>
#include <scan2lod/visualize/scene.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace scan2lod::cli {

void add_render_command(CLI::App& app) {
  struct Args {
    std::string model, output, percents = "100,80,60,40,20", size = "400x400", mode = "both", structure;
    std::string camera;
    double azimuth = 0, elevation = 0;
    bool json = false, no_captions = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("render", "Levels of a .mco model -> one PNG montage (off-screen)");
  cmd->add_option("model", args->model, "Model written by scan2lod build (.mco)")->required();
  cmd->add_option("-o,--output", args->output, "Output picture (.png)")->required();
  cmd->add_option("--percent", args->percents,
                  "Levels as percentages (of the LOD array for the octree, of the full-detail triangles for the "
                  "clusters), comma-separated")
      ->capture_default_str();
  cmd->add_option("--structure", args->structure,
                  "LOD structure to take the levels from: clusters or octree (default: clusters when the model "
                  "has them)")
      ->check(CLI::IsMember(structure_names()));
  cmd->add_option("--size", args->size, "Pixels per panel, WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--mode", args->mode, "shaded, wireframe, or both (wireframe beside shaded per level)")
      ->capture_default_str();
  cmd->add_option("--azimuth", args->azimuth, "Turn the camera about the up axis (degrees)")->capture_default_str();
  cmd->add_option("--elevation", args->elevation, "Raise the camera (degrees)")->capture_default_str();
  CLI::Option* camera =
      cmd->add_option("--camera", args->camera,
                      "A camera in full instead of the framing: EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV (eye, target, up, "
                      "vertical field of view in degrees) in the inputs' frame, as the web page's camera");
  for (CLI::Option* turn : {cmd->get_option("--azimuth"), cmd->get_option("--elevation")}) turn->excludes(camera);
  cmd->add_flag("--no-captions", args->no_captions, "No caption under each panel");
  cmd->add_flag("--json", args->json, "Print the panels as JSON");
  cmd->callback([args] {
    MontageOptions options;
    const std::vector<double> percents = parse_percent_list(args->percents, "--percent");
    parse_size(args->size, "--size", &options.panel_width, &options.panel_height);
    options.mode = parse_render_mode(args->mode);
    options.azimuth = args->azimuth;
    options.elevation = args->elevation;
    if (!args->camera.empty()) options.camera = parse_view_camera(args->camera, "--camera");
    options.captions = !args->no_captions;
    check_png_output(args->output);
    check_output_path(args->output);
    const LodModel model = load_model(args->model);  // file errors first, then the display
    const LodStructure structure = structure_named(model, args->structure, args->model);
    require_display("render");
    const Montage m = render_montage(model, structure, percents, options, args->output);
    const bool octree = structure == LodStructure::kOctree;
    if (args->json) {
      nlohmann::ordered_json j = {{"structure", structure_name(structure)}, {"width", m.width},
                                  {"height", m.height}, {"output", args->output}};
      j["panels"] = nlohmann::ordered_json::array();
      for (const MontagePanel& p : m.panels)
        j["panels"].push_back({{"percent", p.percent}, {"wireframe", p.mode == RenderMode::wireframe},
                               {"triangles", p.triangles}, {"vertices", p.vertices}, {"priority", p.priority},
                               {"error", p.error}, {"clusters", p.clusters}});
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    if (octree) say("%6s %10s %10s %10s\n", "LOD %", "priority", "triangles", "vertices");
    else say("%6s %12s %10s %10s %10s\n", "LOD %", "error", "clusters", "triangles", "vertices");
    const std::size_t step = options.mode == RenderMode::both ? 2 : 1;
    for (std::size_t i = 0; i < m.panels.size(); i += step) {
      const MontagePanel& p = m.panels[i];
      if (octree) say("%6g %10zu %10zu %10zu\n", p.percent, p.priority, p.triangles, p.vertices);
      else say("%6g %12.6g %10zu %10zu %10zu\n", p.percent, p.error, p.clusters, p.triangles, p.vertices);
    }
    say("%zu panels, %dx%d pixels -> %s\n", m.panels.size(), m.width, m.height, args->output.c_str());
  });
}

}  // namespace scan2lod::cli
