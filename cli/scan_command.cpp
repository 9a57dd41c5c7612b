#include "cli/commands.h"

namespace scan2lod::cli {

void add_scan_command(CLI::App& app) { (void)app; }

}  // namespace scan2lod::cli
