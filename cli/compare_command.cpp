#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/core/error.h>
#include <scan2lod/measure/compare_files.h>
#include <scan2lod/measure/comparison_json.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>
#include <string>

namespace scan2lod::cli {
namespace {

void print_table(const std::string& a, const std::string& b, const SurfaceComparison& c) {
  say("A: %s\nB: %s\nB's bounding-box diagonal: %.6g (percentages below are of it)\n\n",
              a.c_str(), b.c_str(), c.diagonal);
  const double scale = c.diagonal > 0 ? 100.0 / c.diagonal : 0.0;
  say("%-8s %10s  %-22s  %-22s  %-22s  %s\n", "", "samples", "mean", "rms", "p95", "max");
  auto row = [&](const char* name, const DistanceStats& s) {
    say("%-8s %10zu", name, s.samples);
    const double values[] = {s.mean, s.rms, s.p95, s.max};
    for (int i = 0; i < 4; ++i) {
      char cell[64];
      std::snprintf(cell, sizeof cell, "%.4e (%.4f%%)", values[i], values[i] * scale);
      say(i < 3 ? "  %-22s" : "  %s\n", cell);
    }
  };
  row("A -> B", c.a_to_b);
  row("B -> A", c.b_to_a);

  say("\n%-28s %12s %12s\n", "topology", "A", "B");
  const MeshTopology& ta = c.a;
  const MeshTopology& tb = c.b;
  auto line = [](const char* name, long long x, long long y) {
    say("%-28s %12lld %12lld\n", name, x, y);
  };
  line("vertices", (long long)ta.vertices, (long long)tb.vertices);
  line("referenced vertices", (long long)ta.referenced_vertices, (long long)tb.referenced_vertices);
  line("triangles", (long long)ta.triangles, (long long)tb.triangles);
  line("edges", (long long)ta.edges, (long long)tb.edges);
  line("boundary edges", (long long)ta.boundary_edges, (long long)tb.boundary_edges);
  line("boundary loops", (long long)ta.boundary_loops, (long long)tb.boundary_loops);
  line("non-manifold edges", (long long)ta.non_manifold_edges, (long long)tb.non_manifold_edges);
  line("components", (long long)ta.components, (long long)tb.components);
  line("largest component (tris)", (long long)ta.largest_component_triangles,
       (long long)tb.largest_component_triangles);
  line("degenerate triangles", (long long)ta.degenerate_triangles, (long long)tb.degenerate_triangles);
  line("Euler characteristic", ta.euler_characteristic, tb.euler_characteristic);
}

}  // namespace

void add_compare_command(CLI::App& app) {
  struct Args {
    std::string a, b;
    CompareOptions options;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Metro distance between two meshes (both directions) and their topology");
  cmd->add_option("A", args->a, "Mesh to measure (.ply .obj .off .stl .vtp .glb .gltf)")->required();
  cmd->add_option("B", args->b, "Reference mesh; its bounding-box diagonal scales the percentages")
      ->required();
  cmd->add_option("--samples", args->options.samples,
                  "Surface samples per direction (0: max(10 x triangles, 100000))")
      ->capture_default_str();
  cmd->add_option("--seed", args->options.seed, "Sampling seed")->capture_default_str();
  cmd->add_flag("--json", args->json, "Print one JSON object instead of a table");
  cmd->callback([args] {
    const MeshPair meshes = read_in_one_frame(args->a, args->b);
    const SurfaceComparison c = compare_named(meshes.a, meshes.b, args->options, args->a, args->b);
    if (args->json) {
      const nlohmann::json out = comparison_json(c);
      std::printf("%s\n", out.dump(2).c_str());
    } else {
      print_table(args->a, args->b, c);
    }
  });
}

}  // namespace scan2lod::cli
