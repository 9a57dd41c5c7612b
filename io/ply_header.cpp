#include <scan2lod/io/ply_header.h>

#include <scan2lod/core/error.h>

#include <cctype>
#include <fstream>
#include <sstream>

namespace scan2lod {
namespace {

constexpr std::size_t kScanHeaderLines = 10000;

bool is_blank(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

// The words a stream of words reads from `text`.
std::vector<std::string> split_words(const std::string& text) {
  std::vector<std::string> words;
  for (std::size_t at = 0; at < text.size();) {
    while (at < text.size() && is_blank(text[at])) ++at;
    const std::size_t start = at;
    while (at < text.size() && !is_blank(text[at])) ++at;
    if (at > start) words.push_back(text.substr(start, at - start));
  }
  return words;
}

// Word `i` of the line, "" past its last.
const std::string& word(const PlyHeaderLine& line, std::size_t i) {
  static const std::string none;
  return i < line.words.size() ? line.words[i] : none;
}

// The text after the line's keyword and the blanks that follow it.
std::string after_keyword(const std::string& text) {
  std::size_t at = 0;
  while (at < text.size() && is_blank(text[at])) ++at;
  while (at < text.size() && !is_blank(text[at])) ++at;
  while (at < text.size() && is_blank(text[at])) ++at;
  return text.substr(at);
}

// What one line after "ply" declares, added to `h`.
void read_declaration(const PlyHeaderLine& line, PlyHeader* h) {
  const std::string& key = word(line, 0);
  if (key == "format") {
    const std::string& f = word(line, 1);
    h->has_format = true;
    if (f == "ascii") h->format = PlyHeader::Format::ascii;
    else if (f == "binary_little_endian") h->format = PlyHeader::Format::binary_le;
    else if (f == "binary_big_endian") h->format = PlyHeader::Format::binary_be;
  } else if (key == "element") {
    PlyElement e;
    e.name = word(line, 1);
    long long count = -1;
    if (line.words.size() > 2) read_ply_count(line.words[2], &count);
    e.count = count > 0 ? std::size_t(count) : 0;
    e.line = line;
    h->elements.push_back(std::move(e));
  } else if (key == "property") {
    if (h->elements.empty()) return;
    PlyProperty p;
    p.type = word(line, 1);
    const bool list = p.type == "list";
    if (list) p.count_type = word(line, 2), p.index_type = word(line, 3);
    p.name = word(line, list ? 4 : 2);
    p.line = line;
    h->elements.back().properties.push_back(std::move(p));
  } else if (key == "obj_info") {
    const std::string rest = after_keyword(line.text);
    h->obj_info.push_back({line.number, rest, split_words(rest)});
  } else if (key == "end_header") {
    h->ended = true;
  } else if (key != "comment" && !key.empty()) {
    h->ignored.push_back(line);
  }
}

// The scan readers' rules for one line after "ply"; `element_seen`: an
// element line came before.
void check_scan_header_line(const std::string& path, const PlyHeaderLine& line, bool* element_seen) {
  if (line.number > kScanHeaderLines) throw InputError(path, "PLY header has no 'end_header' in 10000 lines");
  if (!line.text.empty() && is_blank(line.text[0]))
    fail_at(path, line, "starts with blanks; a header line starts with its keyword");
  const std::string& key = word(line, 0);
  if (key == "format") {
    const std::string& f = word(line, 1);
    if (f != "ascii" && f != "binary_little_endian" && f != "binary_big_endian")
      fail_at(path, line, "expected ascii, binary_little_endian or binary_big_endian");
  } else if (key == "element") {
    long long count = -1;
    if (line.words.size() > 2) read_ply_count(line.words[2], &count);
    if (count < 0) fail_at(path, line, "expected 'element NAME COUNT' with COUNT >= 0");
    *element_seen = true;
  } else if (key == "property") {
    if (!*element_seen) fail_at(path, line, "a property before any element");
  }
}

}  // namespace

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

bool read_ply_count(const std::string& word, long long* count) {
  std::istringstream in(word);
  return bool(in >> *count);
}

PlyHeader parse_ply_header(std::istream& in, std::size_t max_lines) {
  PlyHeader h;
  std::string text;
  while (!h.ended && h.lines.size() < max_lines && std::getline(in, text)) {
    h.bytes += text.size() + 1;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    h.lines.push_back({h.lines.size() + 1, text, split_words(text)});
    const PlyHeaderLine& line = h.lines.back();
    if (line.number > 1) read_declaration(line, &h);
    else if (text.rfind("ply", 0) != 0 && text.rfind("PLY", 0) != 0) break;
  }
  return h;
}

PlyHeader read_ply_header(const std::string& path, std::istream& in) {
  PlyHeader h = parse_ply_header(in, kScanHeaderLines + 1);
  if (h.lines.empty() || h.lines[0].text.rfind("ply", 0) != 0)
    throw InputError(path, "not a PLY file (the first line must be 'ply')");
  bool element_seen = false;
  for (std::size_t i = 1; i < h.lines.size(); ++i) check_scan_header_line(path, h.lines[i], &element_seen);
  if (!h.ended) throw InputError(path, "PLY header ends before 'end_header'");
  return h;
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
