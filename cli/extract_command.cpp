// scan2lod extract: one mesh out of a .mco model, taken by reference
// (seed 003 §6.1-6.2) at a priority chosen by percent, triangle budget or
// priority number.
#include "cli/commands.h"
#include "core/error.h"
#include "io/mesh_file.h"
#include "lod/extract.h"
#include "lod/model_file.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

namespace scan2lod::cli {

void add_extract_command(CLI::App& app) {
  struct Args {
    std::string model, output;
    double percent = 0;
    long long triangles = 0;
    long long priority = 0;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("extract", "One level of detail of a .mco model -> mesh");
  cmd->add_option("model", args->model, "Model written by scan2lod build (.mco)")->required();
  cmd->add_option("-o,--output", args->output, "Output mesh (.ply .obj .stl .off .vtp)")->required();
  CLI::Option* percent =
      cmd->add_option("--percent", args->percent, "The first P % of the LOD array (0 to 100; 100: full detail)");
  CLI::Option* triangles =
      cmd->add_option("--triangles", args->triangles, "The finest level with at most T triangles");
  CLI::Option* priority =
      cmd->add_option("--priority", args->priority, "The level after N expansions (0: the root's mesh)");
  cmd->add_flag("--json", args->json,
                "Print {\"priority\", \"triangles\", \"vertices\", \"extract_seconds\"} as JSON");
  cmd->callback([args, percent, triangles, priority] {
    const int given = int(percent->count() > 0) + int(triangles->count() > 0) + int(priority->count() > 0);
    if (given != 1)
      throw InputError("", "extract needs exactly one of --percent, --triangles and --priority, got " +
                               std::to_string(given));
    if (percent->count() && !(args->percent >= 0 && args->percent <= 100))
      throw InputError("", "--percent must be between 0 and 100, got " + percent->as<std::string>());
    if (triangles->count() && args->triangles < 0)
      throw InputError("", "--triangles must not be negative, got " + std::to_string(args->triangles));
    if (priority->count() && args->priority < 0)
      throw InputError("", "--priority must not be negative, got " + std::to_string(args->priority));
    check_mesh_output(args->output);

    const LodModel model = load_model(args->model);
    std::size_t p;
    if (percent->count()) {
      p = priority_for_percent(model.lod, args->percent);
    } else if (triangles->count()) {
      p = priority_for_triangles(model.lod, args->triangles);
    } else {
      if (std::size_t(args->priority) > model.lod.full())
        throw InputError(args->model, "--priority " + std::to_string(args->priority) + " is past the model's " +
                                          std::to_string(model.lod.full()) + " expansions");
      p = std::size_t(args->priority);
    }

    const auto start = std::chrono::steady_clock::now();
    std::vector<std::uint8_t> scratch;
    std::vector<Triangle> tris;
    extract_lod(model.tree, model.lod, p, &scratch, &tris);
    const TriangleMesh mesh = compact_lod(model.tree, tris);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_mesh(args->output, mesh);

    if (args->json) {
      const nlohmann::ordered_json j = {{"priority", p},
                                {"triangles", mesh.triangles.size()},
                                {"vertices", mesh.positions.size()},
                                {"extract_seconds", seconds}};
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      const double share = model.lod.full() ? 100.0 * double(p) / double(model.lod.full()) : 100.0;
      std::printf("priority %zu of %zu (%.1f %%), %zu triangles, %zu vertices, extracted in %.2f ms -> %s\n", p,
                  model.lod.full(), share, mesh.triangles.size(), mesh.positions.size(), seconds * 1e3,
                  args->output.c_str());
    }
  });
}

}  // namespace scan2lod::cli
