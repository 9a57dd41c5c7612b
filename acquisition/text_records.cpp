#include <scan2lod/acquisition/text_records.h>

#include <scan2lod/core/error.h>

#include <fstream>

namespace scan2lod {

std::string read_file_from(const std::string& path, std::size_t offset) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw InputError(path, "cannot tell the file's size");
  std::string text(std::size_t(size) > offset ? std::size_t(size) - offset : 0, '\0');
  in.seekg(std::streamoff(offset));
  in.read(text.data(), std::streamsize(text.size()));
  text.resize(std::size_t(in.gcount()));  // a file that shrank meanwhile
  return text;
}

}  // namespace scan2lod
