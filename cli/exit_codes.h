// The command line's exit codes, one per kind of failure a script can act on.
#pragma once

namespace scan2lod::cli {

constexpr int kExitOk = 0;
constexpr int kExitInput = 1;     // an input, output or request was refused (the message says which)
constexpr int kExitUsage = 2;     // unknown flag, missing argument, malformed value
constexpr int kExitMemory = 3;    // out of memory
constexpr int kExitInternal = 4;  // anything else: a bug, please report it

// The text `--help` ends with.
inline const char* exit_code_help() {
  return "Exit codes: 0 done; 1 an input, output or request was refused (the message names the file and "
         "what was expected); 2 usage error (unknown flag, missing or malformed argument); 3 out of memory; "
         "4 internal error.";
}

}  // namespace scan2lod::cli
