// How fast the text readers parse, against the disk: each case reads its
// files with scan2lod's reader and with `cat FILES > /dev/null`, in the same
// run, files warm in the page cache, and reports both in MB/s (issue 32's
// target: 150 MB/s or more for ASCII range grids and clouds).
//
// The cases are written here from the bundled data, in the forms archives
// publish: the ten bunny scans as ASCII range-grid PLYs (as Stanford's
// originals, "%g" numbers), and the scans merged into one cloud with normals
// as .xyz, .pts, ASCII PCD and ASCII vertex PLY; a LAS file of the same
// points (binary) for comparison. Stanford's ASCII originals are read too
// when ../shared/data/bunny/data is beside the checkout.
//
//   scan2lod_bench_io [--runs N] [--copies K]
//     --runs    timed runs per case, the median reported (default 5)
//     --copies  the merged cloud written K times over into each cloud file,
//               for files large enough to use both cores (default 1)
#include <scan2lod/acquisition/las_file.h>
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/acquisition/organized_pcd.h>
#include <scan2lod/acquisition/point_cloud_files.h>
#include <scan2lod/acquisition/range_grid_ply.h>
#include <scan2lod/bench/bench_support.h>
#include <scan2lod/core/progress.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

using namespace scan2lod;
using namespace scan2lod::bench;
namespace fs = std::filesystem;

namespace {

// A range image as Stanford's ASCII originals are written: the valid samples
// as vertices, then one line per cell ("0" or "1 INDEX").
void write_ascii_grid(const std::string& path, const RangeImage& image) {
  std::string body;
  std::size_t vertices = 0;
  for (const Vec3f& p : image.points)
    if (std::isfinite(p.x())) body += format("%g %g %g \n", p.x(), p.y(), p.z()), ++vertices;
  std::size_t next = 0;
  for (const Vec3f& p : image.points) body += std::isfinite(p.x()) ? format("1 %zu \n", next++) : std::string("0 \n");
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat ascii 1.0\nobj_info num_cols " << image.cols << "\nobj_info num_rows " << image.rows
      << "\nelement vertex " << vertices << "\nproperty float x\nproperty float y\nproperty float z\n"
      << "element range_grid " << image.points.size() << "\nproperty list uchar int vertex_indices\nend_header\n"
      << body;
}

enum class CloudText { xyz, pts, pcd, ply };

// The points with their normals, `copies` times over, as text.
void write_cloud_text(const std::string& path, const OrientedPoints& points, int copies, CloudText kind) {
  const std::size_t n = points.size() * std::size_t(copies);
  std::ofstream out(path, std::ios::binary);
  if (kind == CloudText::pts) out << n << "\n";
  if (kind == CloudText::pcd)
    out << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\n"
        << "TYPE F F F F F F\nCOUNT 1 1 1 1 1 1\nWIDTH " << n << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << n
        << "\nDATA ascii\n";
  if (kind == CloudText::ply)
    out << "ply\nformat ascii 1.0\nelement vertex " << n << "\nproperty float x\nproperty float y\n"
        << "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n";
  std::string line;
  for (int c = 0; c < copies; ++c)
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vec3f& p = points.positions[i];
      const Vec3f& q = points.normals[i];
      // .pts: x y z intensity, as scanners export them; the rest: x y z nx ny nz.
      line = kind == CloudText::pts ? format("%g %g %g %d\n", p.x(), p.y(), p.z(), int(i % 2048))
                                    : format("%g %g %g %g %g %g\n", p.x(), p.y(), p.z(), q.x(), q.y(), q.z());
      out << line;
    }
}

// A LAS 1.2 file of the points (format 0, 1 mm scale, UTM-sized offsets).
void write_las(const std::string& path, const OrientedPoints& points, int copies) {
  const std::uint32_t n = std::uint32_t(points.size() * std::size_t(copies));
  std::string h(227, '\0');
  auto put = [&h](std::size_t at, auto v) { std::memcpy(&h[at], &v, sizeof v); };
  std::memcpy(&h[0], "LASF", 4);
  h[24] = 1, h[25] = 2;
  put(94, std::uint16_t(227)), put(96, std::uint32_t(227)), put(104, std::uint8_t(0)), put(105, std::uint16_t(20));
  put(107, n);
  const double scale = 1e-6, offset[3] = {500000, 5000000, 300};
  for (int a = 0; a < 3; ++a) put(131 + 8 * a, scale), put(155 + 8 * a, offset[a]);
  for (int a = 0; a < 3; ++a) put(179 + 16 * a, offset[a] + 1), put(187 + 16 * a, offset[a] - 1);
  std::ofstream out(path, std::ios::binary);
  out << h;
  char record[20] = {};
  for (int c = 0; c < copies; ++c)
    for (const Vec3f& p : points.positions) {
      for (int a = 0; a < 3; ++a) {
        const std::int32_t v = std::int32_t(std::lround(double(p[a]) / scale));
        std::memcpy(record + 4 * a, &v, 4);
      }
      out.write(record, 20);
    }
}

std::uintmax_t bytes_of(const std::vector<std::string>& files) {
  std::uintmax_t total = 0;
  for (const std::string& f : files) total += fs::file_size(f);
  return total;
}

double time_cat(const std::vector<std::string>& files) {
  std::string command = "cat";
  for (const std::string& f : files) command += " '" + f + "'";
  command += " > /dev/null";
  const auto start = Clock::now();
  if (std::system(command.c_str()) != 0) throw std::runtime_error("cat failed: " + command);
  return seconds_since(start);
}

struct Case {
  std::string name;
  std::vector<std::string> files;
  std::function<std::size_t(const std::string&)> read;  // returns the points read, to keep the work
};

}  // namespace

int main(int argc, char** argv) {
  int runs = 5, copies = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--runs") == 0) runs = std::max(1, std::atoi(argv[i + 1]));
    else if (std::strcmp(argv[i], "--copies") == 0) copies = std::max(1, std::atoi(argv[i + 1]));
  }
  Progress::set_quiet(true);
  ScratchDir dir("scan2lod_io_bench");
  const std::string conf = std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf";

  std::vector<std::string> grids;
  for (const ConfEntry& e : read_conf(conf)) {
    grids.push_back(dir.path(fs::path(e.file).filename().string()));
    write_ascii_grid(grids.back(), read_range_grid_ply(e.file));
  }
  const OrientedPoints merged = load_oriented_points({conf});
  const std::string xyz = dir.path("bunny.xyz"), pts = dir.path("bunny.pts"), pcd = dir.path("bunny.pcd"),
                    ply = dir.path("bunny_cloud.ply"), las = dir.path("bunny.las");
  write_cloud_text(xyz, merged, copies, CloudText::xyz);
  write_cloud_text(pts, merged, copies, CloudText::pts);
  write_cloud_text(pcd, merged, copies, CloudText::pcd);
  write_cloud_text(ply, merged, copies, CloudText::ply);
  write_las(las, merged, copies);

  // Stanford's own ASCII originals, when ../shared is beside the checkout.
  std::vector<std::string> originals;
  for (const std::string& g : grids) {
    const fs::path original = fs::path(SCAN2LOD_SOURCE_DIR) / ".." / "shared" / "data" / "bunny" / "data" /
                              fs::path(g).filename();
    if (fs::exists(original)) originals.push_back(original.string());
  }
  std::vector<Case> cases = {
      {"ASCII range grids (10 bunny scans)", grids,
       [](const std::string& f) { return read_range_grid_ply(f).points.size(); }},
      {".xyz (x y z nx ny nz)", {xyz}, [](const std::string& f) { return read_point_cloud_text(f).size(); }},
      {".pts (count, x y z i)", {pts}, [](const std::string& f) { return read_point_cloud_text(f).size(); }},
      {"ASCII PCD (x y z normal_*)", {pcd}, [](const std::string& f) { return read_unorganized_pcd(f).size(); }},
      {"ASCII PLY vertices", {ply}, [](const std::string& f) { return read_point_cloud_ply(f).size(); }},
      {"LAS 1.2 format 0 (binary)", {las}, [](const std::string& f) { return read_las(f).size(); }},
  };
  if (originals.size() == grids.size())
    cases.insert(cases.begin() + 1, {"ASCII range grids (Stanford's originals)", originals,
                                     [](const std::string& f) { return read_range_grid_ply(f).points.size(); }});
  std::printf("%s\n\n", run_header_line(load_average(), load_average()).c_str());
  std::printf("| input | MB | points | cat MB/s | read MB/s | read s | read / cat |\n|---|---|---|---|---|---|---|\n");
  for (const Case& c : cases) {
    const double mb = double(bytes_of(c.files)) / 1e6;
    time_cat(c.files);  // into the page cache
    std::vector<double> cat, read;
    std::size_t points = 0;
    for (int r = 0; r < runs; ++r) {
      cat.push_back(time_cat(c.files));
      const auto start = Clock::now();
      points = 0;
      for (const std::string& f : c.files) points += c.read(f);
      read.push_back(seconds_since(start));
    }
    const double cat_s = median(cat), read_s = median(read);
    std::printf("| %s | %.1f | %zu | %.0f | %.0f | %.3f | %.2f |\n", c.name.c_str(), mb, points, mb / cat_s,
                mb / read_s, read_s, cat_s / read_s);
    std::fflush(stdout);
  }
  return 0;
}
