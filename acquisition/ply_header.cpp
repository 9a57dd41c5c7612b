#include "acquisition/ply_header.h"

#include "core/error.h"

#include <cctype>
#include <fstream>
#include <sstream>

namespace scan2lod {

std::string shown_line(const std::string& line) {
  std::string s = line.substr(0, 60);
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return line.size() > 60 ? s + "..." : s;
}

void fail_at(const std::string& path, const PlyHeaderLine& line, const std::string& what) {
  throw InputError(path, "header line " + std::to_string(line.number) + " ('" + shown_line(line.text) + "'): " + what);
}

std::size_t ply_scalar_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

PlyHeader read_ply_header(const std::string& path, std::istream& in) {
  PlyHeader h;
  std::string text;
  if (!std::getline(in, text) || text.rfind("ply", 0) != 0)
    throw InputError(path, "not a PLY file (the first line must be 'ply')");
  h.bytes = text.size() + 1;
  for (std::size_t n = 2; std::getline(in, text); ++n) {
    h.bytes += text.size() + 1;
    h.lines = n;
    if (n > 10000) throw InputError(path, "PLY header has no 'end_header' in 10000 lines");
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const PlyHeaderLine line{n, text};
    if (!text.empty() && std::isspace(static_cast<unsigned char>(text[0])))
      fail_at(path, line, "starts with blanks; a header line starts with its keyword");
    std::istringstream ls(text);
    std::string key;
    ls >> key;
    if (key == "format") {
      std::string f;
      ls >> f;
      h.has_format = true;
      if (f == "ascii") h.format = PlyHeader::Format::ascii;
      else if (f == "binary_little_endian") h.format = PlyHeader::Format::binary_le;
      else if (f == "binary_big_endian") h.format = PlyHeader::Format::binary_be;
      else fail_at(path, line, "expected ascii, binary_little_endian or binary_big_endian");
    } else if (key == "element") {
      PlyElement e;
      long long count = -1;
      ls >> e.name >> count;
      if (count < 0) fail_at(path, line, "expected 'element NAME COUNT' with COUNT >= 0");
      e.count = std::size_t(count);
      e.line = line;
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) fail_at(path, line, "a property before any element");
      PlyProperty p;
      ls >> p.type;
      if (p.type == "list") ls >> p.count_type >> p.index_type;
      ls >> p.name;
      p.line = line;
      h.elements.back().properties.push_back(std::move(p));
    } else if (key == "obj_info") {
      std::string rest;
      std::getline(ls >> std::ws, rest);
      h.obj_info.push_back({n, rest});
    } else if (key == "end_header") {
      return h;
    } else if (key != "comment" && !key.empty()) {
      h.ignored.push_back(line);
    }
  }
  throw InputError(path, "PLY header ends before 'end_header'");
}

std::string ignored_lines_warning(const std::string& path, const PlyHeader& header) {
  if (header.ignored.empty()) return "";
  const PlyHeaderLine& first = header.ignored.front();
  const std::size_t more = header.ignored.size() - 1;
  return path + ": header line " + std::to_string(first.number) + " ('" + shown_line(first.text) + "')" +
         (more ? " and " + std::to_string(more) + " more" : "") +
         ": no PLY keyword (ply, format, comment, obj_info, element, property, end_header); skipped";
}

std::string ply_header_warning(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  try {
    return ignored_lines_warning(path, read_ply_header(path, in));
  } catch (const InputError&) {
    return "";
  }
}

}  // namespace scan2lod
