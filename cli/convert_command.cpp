#include <scan2lod/acquisition/scan_set.h>
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/cli/usage.h>
#include <scan2lod/io/atomic_file.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace scan2lod::cli {

void add_convert_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> inputs;
    std::string output;
    std::string conf_name = "scans.conf";
    int threads = 0;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "convert", "Scan set (.conf, range-grid PLYs, organized PCDs) -> binary range-grid PLYs + .conf");
  cmd->add_option("inputs", args->inputs, "A .conf, range-grid PLYs or organized PCDs")->required();
  cmd->add_option("-o,--output", args->output, "Output folder")->required();
  cmd->add_option("--conf", args->conf_name, "Name of the .conf written in the folder")->capture_default_str();
  add_threads_option(cmd, &args->threads);
  cmd->add_flag("--json", args->json, "Print the counts as JSON");
  cmd->callback([args] {
    const auto start = std::chrono::steady_clock::now();
    check_output_folder(args->output);
    std::vector<PlacedScan> scans = read_scan_set(args->inputs, usable_threads(args->threads));
    write_scan_set(args->output, scans, args->conf_name);
    std::size_t samples = 0;
    for (const PlacedScan& s : scans)
      for (const Vec3f& p : s.image.points) samples += std::isfinite(p.x());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string conf = (std::filesystem::path(args->output) / args->conf_name).string();
    if (args->json) {
      const nlohmann::ordered_json j = {{"scans", scans.size()}, {"samples", samples}, {"seconds", seconds},
                                        {"output", conf}};
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    say("%zu scans, %zu samples, %.2f s -> %s\n", scans.size(), samples, seconds, conf.c_str());
  });
}

}  // namespace scan2lod::cli
