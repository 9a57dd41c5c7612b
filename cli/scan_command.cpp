// `scan2lod scan MESH -o DIR`: virtual range scans of a mesh (Lee 2007, §4.4),
// written as a Stanford-style scan set that `reconstruct` reads back.
#include <scan2lod/acquisition/virtual_scanner.h>
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/mesh_file.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <regex>
#include <string>

namespace scan2lod::cli {
namespace {

struct ScanArgs {
  std::string mesh;
  std::string out_dir;
  std::string size = "256x256";
  VirtualScanOptions options;
  bool json = false;
};

// "WxH" with both in [1, 16384]; returns false on anything else.
bool parse_size(const std::string& text, int& width, int& height) {
  static const std::regex pattern(R"(^\s*(\d{1,5})\s*[xX]\s*(\d{1,5})\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, pattern)) return false;
  width = std::stoi(m[1]);
  height = std::stoi(m[2]);
  return width >= 1 && height >= 1 && width <= 16384 && height <= 16384;
}

void run(ScanArgs& args) {
  parse_size(args.size, args.options.width, args.options.height);  // validated by CLI11
  check_output_folder(args.out_dir);
  const TriangleMesh mesh = read_mesh(args.mesh);
  const std::vector<VirtualScan> scans = virtual_scan(mesh, args.options);
  write_scan_set(args.out_dir, scans);
  std::size_t samples = 0;
  for (const VirtualScan& s : scans)
    for (const Vec3f& p : s.image.points) samples += !std::isnan(p.x());
  if (args.json) {
    const nlohmann::ordered_json j = {{"mesh", args.mesh}, {"views", scans.size()}, {"width", args.options.width},
                                      {"height", args.options.height}, {"samples", samples},
                                      {"output", args.out_dir + "/scans.conf"}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  say("scanned %s: %zu views of %dx%d, %zu samples -> %s/scans.conf\n",
              args.mesh.c_str(), scans.size(), args.options.width, args.options.height, samples,
              args.out_dir.c_str());
}

}  // namespace

void add_scan_command(CLI::App& app) {
  auto args = std::make_shared<ScanArgs>();
  CLI::App* cmd = app.add_subcommand(
      "scan", "Generate virtual range scans of a mesh (orthographic views on a sphere)");
  cmd->add_option("mesh", args->mesh, "Mesh to scan (.ply, .obj, .off, .stl, .vtp, .glb, .gltf)")
      ->required();
  cmd->add_option("-o,--output", args->out_dir,
                  "Folder for scan_000.ply ... and scans.conf (created if missing)")
      ->required();
  cmd->add_option("--views", args->options.views, "Number of view directions")
      ->default_val(args->options.views)
      ->check(CLI::Range(1, 10000));
  cmd->add_option("--size", args->size, "Lattice size per view, WIDTHxHEIGHT")
      ->default_val(args->size)
      ->check(CLI::Validator(
          [](std::string& text) {
            int w, h;
            if (parse_size(text, w, h)) return std::string();
            return "expected WIDTHxHEIGHT such as 256x256 (each 1..16384), got '" + text + "'";
          },
          "WxH"));
  cmd->add_flag("--json", args->json, "Print the counts as JSON");
  cmd->callback([args] { run(*args); });
}

}  // namespace scan2lod::cli
