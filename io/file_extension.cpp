#include <scan2lod/io/file_extension.h>

#include <cctype>
#include <filesystem>

namespace scan2lod {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace scan2lod
