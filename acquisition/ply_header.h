// The header of a PLY file, read once for both PLY readers (range grids,
// acquisition/range_grid_ply.h, and vertex-only point clouds,
// acquisition/point_cloud_files.h). Each judges the elements it finds
// itself; every complaint names the header line it is about.
#pragma once

#include <cstddef>
#include <istream>
#include <string>
#include <vector>

namespace scan2lod {

struct PlyHeaderLine {
  std::size_t number = 0;  // 1 for "ply"
  std::string text;
};

struct PlyProperty {
  std::string type, name;          // type "list" for a list
  std::string count_type, index_type;  // a list's
  PlyHeaderLine line;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
  PlyHeaderLine line;
};

struct PlyHeader {
  enum class Format { ascii, binary_le, binary_be } format = Format::ascii;
  bool has_format = false;
  std::size_t bytes = 0;  // up to and with the end_header line
  std::size_t lines = 0;  // the same, in lines
  std::vector<PlyElement> elements;
  std::vector<PlyHeaderLine> obj_info;  // the text after the keyword
  // Lines of no keyword the format knows, outside any definition (Stanford's
  // happy_stand scans carry 'bye' lines among their obj_info): skipped.
  std::vector<PlyHeaderLine> ignored;
};

// Reads the header from `in` (left at the body's first byte). A line whose
// keyword is none of ply, format, comment, obj_info, element, property and
// end_header carries nothing a reader needs: it is listed in `ignored`, as
// PCL's reader (which earlier releases used) skips it. Throws InputError
// naming `path` and the line for a malformed format, element or property
// line, for a line that starts with blanks (PCL's reader aborts on those),
// or for a header without end_header within 10,000 lines.
PlyHeader read_ply_header(const std::string& path, std::istream& in);

// Throws InputError: "header line N ('...'): what".
[[noreturn]] void fail_at(const std::string& path, const PlyHeaderLine& line, const std::string& what);

// Bytes of a PLY scalar type (char ... float64), 0 for an unknown one.
std::size_t ply_scalar_size(const std::string& type);

// The warning for a header's ignored lines, naming the file and the first
// of them; empty when there are none.
std::string ignored_lines_warning(const std::string& path, const PlyHeader& header);

// The same warning for the PLY file at `path`, whatever its elements (a mesh's
// too: io/mesh_file.cpp reads mesh headers for OpenMesh and skips such lines
// without a word). Empty when there are none, or when the header cannot be
// read: then the reader of the file's kind says what is wrong.
std::string ply_header_warning(const std::string& path);

// A line as it may appear in a message: bounded and printable.
std::string shown_line(const std::string& line);

}  // namespace scan2lod
