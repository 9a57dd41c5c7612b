#include "cli/outputs.h"

#include "core/error.h"

#include <algorithm>
#include <filesystem>

namespace scan2lod::cli {

namespace fs = std::filesystem;

void refuse_overwriting_inputs(const std::string& output, const std::vector<std::string>& inputs) {
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(output, ec);
  for (const std::string& input : inputs) {
    const bool same = fs::exists(output, ec) ? fs::equivalent(output, input, ec)
                                             : fs::weakly_canonical(input, ec) == out;
    if (same) throw InputError(output, "is also an input (" + input + "); choose another output name");
  }
}

std::string extension_of(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  if (!ext.empty()) ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

}  // namespace scan2lod::cli
