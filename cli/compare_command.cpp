#include "cli/commands.h"

namespace scan2lod::cli {

void add_compare_command(CLI::App& app) { (void)app; }

}  // namespace scan2lod::cli
