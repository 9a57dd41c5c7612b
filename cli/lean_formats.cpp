// The lean program's .vtp reader and writer: never called, since a command
// line that names a .vtp file runs in scan2lod-full (cli/full_program.h).
// Defined here, they keep the linker from taking io/vtp_file.cpp, and with
// it VTK, from the library.
#include <scan2lod/io/vtp_file.h>

#include <stdexcept>

namespace scan2lod {

TriangleMesh read_vtp(const std::string&, std::vector<Vec3d>*) {
  throw std::logic_error(".vtp files are read by scan2lod-full");
}

void write_vtp(const std::string&, const std::string&, const TriangleMesh&, const Vec3d&) {
  throw std::logic_error(".vtp files are written by scan2lod-full");
}

}  // namespace scan2lod
