#include <scan2lod/cli/outputs.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/file_extension.h>

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
  const std::string ext = lower_extension(path);
  return ext.empty() ? ext : ext.substr(1);
}

}  // namespace scan2lod::cli
