// Checks every command makes on its output paths before long work.
#pragma once

#include <string>
#include <vector>

namespace scan2lod::cli {

// Throws InputError when `output` names one of `inputs` (the same path, or
// another name of the same file): an output never replaces an input.
void refuse_overwriting_inputs(const std::string& output, const std::vector<std::string>& inputs);

// The extension of `path` without its dot, lower case ("" when none).
std::string extension_of(const std::string& path);

}  // namespace scan2lod::cli
