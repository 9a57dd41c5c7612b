#include <scan2lod/io/obj_writer.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/line_writer.h>

#include <cstdio>
#include <memory>

namespace scan2lod {

void write_obj(const std::string& file, const std::string& name, const TriangleMesh& mesh, const Vec3d& origin) {
  const bool framed = origin != Vec3d::Zero();
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "wb"), &std::fclose);
  if (!f) throw InputError(name, "cannot create the file (does the folder exist?)");
  const bool has_n = !mesh.normals.empty(), has_c = !mesh.colors.empty();
  bool failed;
  {
    LineWriter out(f.get());
    out.text("# scan2lod\n");
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      out.text("v");
      for (int k = 0; k < 3; ++k) {
        out.text(" ");
        if (framed) out.number(origin[k] + double(mesh.positions[i][k]));
        else out.number(mesh.positions[i][k]);
      }
      if (has_c)
        for (int k = 0; k < 3; ++k) out.text(" "), out.number(float(mesh.colors[i][k]) / 255.f);
      out.end_line();
    }
    for (std::size_t i = 0; has_n && i < mesh.normals.size(); ++i) {
      out.text("vn");
      for (int k = 0; k < 3; ++k) out.text(" "), out.number(mesh.normals[i][k]);
      out.end_line();
    }
    for (const Triangle& t : mesh.triangles) {
      out.text("f");
      for (int k = 0; k < 3; ++k) {
        out.text(" ");
        out.number((long long)t[k] + 1);
        if (has_n) out.text("//"), out.number((long long)t[k] + 1);
      }
      out.end_line();
    }
    out.flush();
    failed = out.failed();
  }
  if (failed || std::fflush(f.get()) != 0) throw InputError(name, "writing obj failed (disk full?)");
}

}  // namespace scan2lod
