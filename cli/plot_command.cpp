// scan2lod plot: the LOD graphs of a .mco model as VTK charts in one PNG (the
// octree's: Lee 2007, Figs. 6.6-6.8; the cluster hierarchy's: error, clusters
// and vertices against triangles), plus error against triangles given a
// reference mesh.
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/visualize/levels.h>
#include <scan2lod/visualize/montage.h>
#include <scan2lod/visualize/plots.h>
#include <scan2lod/visualize/png_output.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace scan2lod::cli {

void add_plot_command(CLI::App& app) {
  struct Args {
    std::string model, output, reference, percents = "1,2,5,10,20,30,40,50,60,70,80,90,100", size = "520x400";
    std::string structure;
    std::size_t samples = 20000;
    bool linear = false, json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("plot", "LOD metric and accumulation graphs of a .mco model -> PNG");
  cmd->add_option("model", args->model, "Model written by scan2lod build (.mco)")->required();
  cmd->add_option("-o,--output", args->output, "Output picture (.png)")->required();
  cmd->add_option("--reference", args->reference, "Mesh to measure each level against (adds error vs triangles)");
  cmd->add_option("--percent", args->percents, "Levels measured against --reference, comma-separated")
      ->capture_default_str();
  cmd->add_option("--samples", args->samples, "Surface samples per direction and level for --reference")
      ->capture_default_str();
  cmd->add_option("--size", args->size, "Pixels per chart, WIDTHxHEIGHT")->capture_default_str();
  cmd->add_flag("--linear", args->linear, "The LOD metric (octree) or error (clusters) chart on a linear axis "
                                          "(default: log)");
  cmd->add_option("--structure", args->structure,
                  "LOD structure to plot: clusters or octree (default: clusters when the model has them)")
      ->check(CLI::IsMember(structure_names()));
  cmd->add_flag("--json", args->json, "Print the charts and measured levels as JSON");
  cmd->callback([args] {
    PlotOptions options;
    parse_size(args->size, "--size", &options.chart_width, &options.chart_height);
    options.log_metric = !args->linear;
    const std::vector<double> percents = parse_percent_list(args->percents, "--percent");
    check_png_output(args->output);
    check_output_path(args->output);
    const LodModel model = load_model(args->model);  // file errors first, then the display
    const LodStructure structure = structure_named(model, args->structure, args->model);
    const TriangleMesh reference = args->reference.empty() ? TriangleMesh{} : read_mesh(args->reference);
    require_display("plot");
    std::vector<LevelError> errors;
    if (!args->reference.empty()) {
      errors = level_errors(model, structure, reference, percents, args->samples);
      const bool octree = structure == LodStructure::kOctree;
      say("%6s %10s %10s %12s %12s\n", "LOD %", octree ? "priority" : "error", "triangles", "to ref %",
                  "from ref %");
      for (const LevelError& e : errors) {
        if (octree)
          say("%6g %10zu %10zu %12.4f %12.4f\n", e.percent, e.priority, e.triangles, e.mean_to_reference,
                      e.mean_from_reference);
        else
          say("%6g %10.4g %10zu %12.4f %12.4f\n", e.percent, e.error, e.triangles, e.mean_to_reference,
                      e.mean_from_reference);
      }
    }
    const PlotPicture p = write_lod_plots(model, structure, errors, options, args->output);
    if (args->json) {
      nlohmann::ordered_json j = {{"structure", structure_name(structure)}, {"charts", p.charts.size()},
                                  {"full_triangles", p.full_triangles}, {"width", p.width}, {"height", p.height},
                                  {"output", args->output}};
      j["levels"] = nlohmann::ordered_json::array();
      for (const LevelError& e : errors)
        j["levels"].push_back({{"percent", e.percent}, {"triangles", e.triangles}, {"priority", e.priority},
                               {"error", e.error}, {"mean_to_reference_percent", e.mean_to_reference},
                               {"mean_from_reference_percent", e.mean_from_reference}});
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    if (structure == LodStructure::kOctree)
      say("%zu charts (octree: %zu priorities, %lld triangles at full detail), %dx%d pixels -> %s\n",
                  p.charts.size(), p.priorities, (long long)p.full_triangles, p.width, p.height, args->output.c_str());
    else
      say("%zu charts (clusters: %lld triangles at full detail), %dx%d pixels -> %s\n", p.charts.size(),
                  (long long)p.full_triangles, p.width, p.height, args->output.c_str());
  });
}

}  // namespace scan2lod::cli
