#include <scan2lod/cli/app.h>

#include <scan2lod/cli/exit_codes.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/cli/usage.h>
#include <scan2lod/lod/model_file.h>

#include <cstdio>
#include <string>

namespace scan2lod::cli {

int run_app(int argc, char** argv, const std::function<void(CLI::App&)>& add_commands) {
  CLI::App app{"scan2lod: range scans, point clouds and meshes to level-of-detail models"};
  app.require_subcommand(1);
  app.fallthrough();
  app.footer(exit_code_help());
  app.failure_message(usage_failure_message);
  app.set_version_flag("--version", std::string("scan2lod ") + SCAN2LOD_VERSION + " (model format " +
                                        std::to_string(kModelFormatMajor) + "." +
                                        std::to_string(kModelFormatMinor) + ")");
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors (and the JSON asked for with --json)");
  app.parse_complete_callback([&] {
    set_quiet(quiet);
    if (!quiet) install_terminal_progress();
  });
  add_commands(app);
  // CLI11 would take a mistyped command for a missing one.
  if (const std::string unknown = unknown_command_message(app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "scan2lod: error: %s\n", unknown.c_str());
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11's own codes (104-114) say which parse rule failed; users and
    // scripts get one documented code for every usage error.
    return app.exit(e) == 0 ? kExitOk : kExitUsage;
  } catch (...) {
    return print_error();
  }
  return kExitOk;
}

}  // namespace scan2lod::cli
