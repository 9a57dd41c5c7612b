// The header of a PLY file, parsed once for every PLY reader: range grids
// (acquisition/range_grid_ply.h), vertex-only point clouds
// (acquisition/point_cloud_files.h) and meshes (io/mesh_file.h, whose body
// OpenMesh reads, and io/double_positions.h). parse_ply_header() splits the
// lines into words and reads the declarations in them, judging nothing; each
// reader holds the header to its own rules (read_ply_header() for the scan
// readers, OpenMesh's word-by-word reading for meshes), and every complaint
// names the header line it is about.
#pragma once

#include <cstddef>
#include <istream>
#include <string>
#include <vector>

namespace scan2lod {

struct PlyHeaderLine {
  std::size_t number = 0;          // 1 for "ply"
  std::string text;                // without its line end ('\n' and one '\r')
  std::vector<std::string> words;  // as a stream of words reads the text (split at blanks, tabs, '\r')
};

struct PlyProperty {
  std::string type, name;              // type "list" for a list
  std::string count_type, index_type;  // a list's
  PlyHeaderLine line;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;  // COUNT as read_ply_count() reads it; 0 when missing or negative
  std::vector<PlyProperty> properties;
  PlyHeaderLine line;
};

struct PlyHeader {
  enum class Format { ascii, binary_le, binary_be } format = Format::ascii;
  bool has_format = false;
  bool ended = false;     // the last line read is end_header
  std::size_t bytes = 0;  // of the lines read, line ends included: where the body starts when ended
  std::vector<PlyHeaderLine> lines;     // every line read, "ply" first
  std::vector<PlyElement> elements;     // a property before any element belongs to none
  std::vector<PlyHeaderLine> obj_info;  // the text after the keyword
  // Lines of no keyword the format knows, outside any definition (Stanford's
  // happy_stand scans carry 'bye' lines among their obj_info): skipped.
  std::vector<PlyHeaderLine> ignored;
};

// Reads header lines from `in` until end_header (leaving `in` at the body's
// first byte) or until `max_lines` lines are read; only the first when it
// does not start with "ply" or "PLY" (no reader takes such a file). Never
// throws: a line is read as far as it goes (an unknown format leaves
// `format` as it was, a COUNT of no number is 0, a property before any
// element is dropped), and the readers' rules judge the lines.
PlyHeader parse_ply_header(std::istream& in, std::size_t max_lines);

// The header as the scan readers (range grids, point clouds) take it. A line
// whose keyword is none of ply, format, comment, obj_info, element, property
// and end_header carries nothing a reader needs: it is listed in `ignored`,
// as PCL's reader (which earlier releases used) skips it. Throws InputError
// naming `path` and the line for a malformed format, element or property
// line, for a line that starts with blanks (PCL's reader aborts on those),
// or for a header without end_header within 10,000 lines.
PlyHeader read_ply_header(const std::string& path, std::istream& in);

// COUNT of 'element NAME COUNT', read as a stream reads a long long: false
// when `word` is not a number (*count 0) or lies beyond a long long (*count
// the nearest one). Earlier readers took either reading: each keeps its own.
bool read_ply_count(const std::string& word, long long* count);

// Throws InputError: "header line N ('...'): what".
[[noreturn]] void fail_at(const std::string& path, const PlyHeaderLine& line, const std::string& what);

// Bytes of a PLY scalar type (char ... float64), 0 for an unknown one.
std::size_t ply_scalar_size(const std::string& type);

// The warning for a header's ignored lines, naming the file and the first
// of them; empty when there are none.
std::string ignored_lines_warning(const std::string& path, const PlyHeader& header);

// The same warning for the PLY file at `path`, whatever its elements (a mesh's
// too: io/mesh_file.cpp holds mesh headers to OpenMesh's reading and skips
// such lines without a word). Empty when there are none, or when
// read_ply_header() refuses the header: then the reader of the file's kind
// says what is wrong.
std::string ply_header_warning(const std::string& path);

// A line as it may appear in a message: bounded and printable.
std::string shown_line(const std::string& line);

}  // namespace scan2lod
