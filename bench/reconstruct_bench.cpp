// Reconstruction benchmark: scan2lod's sparse marching cubes against PCL's
// MarchingCubesHoppe on the same oriented points, on the Stanford bunny scans.
//
// What is measured, per case, each in its own forked child process:
//   - seconds: wall time of the work alone, timed inside the child.
//       scan2lod R:        reconstruct() on oriented points already in memory,
//                          all threads; median of --runs runs (one child each).
//       scan2lod job R:    load_oriented_points(--input) + reconstruct(), i.e.
//                          everything from files to mesh; median of --runs.
//       PCL R:             MarchingCubesHoppe::reconstruct() (kd-tree build,
//                          dense R^3 grid, polygonisation; single-threaded) on a
//                          PointNormal copy of the same points; one run, killed
//                          after --pcl-timeout seconds if given.
//   - peak MiB: the child's ru_maxrss from wait4(), i.e. its own high-water
//     RSS, also for a child killed at the timeout. It includes what every
//     child inherits from the parent (the loaded points, library pages it
//     touches); the peak of a child that does nothing is printed as the floor.
//   - fidelity: Metro distances (compare_surfaces) between the output and
//     --reference, both directions as % of the reference's diagonal, p95 of
//     output->reference; and the output's triangles, components and boundary
//     loops (mesh_topology). PCL's triangle soup is welded first.
//   - ratio: PCL seconds / scan2lod seconds at the same R, both from this run,
//     because this machine is too noisy for times from different runs to compare.
//
// PCL is made to use scan2lod's grid: same bounding cube, same cube size,
// corners at the same positions (see PclHoppeOnGrid). Its far-corner cut
// (setDistanceIgnore) is scan2lod's undefined-corner rule with one global
// spacing (see pcl_ignore_distance).
//
// Children get the work by fork() without exec, so the parent must never run
// OpenMP itself before the last child is done: libgomp's thread pool does not
// survive fork. The parent therefore loads the points in a child too and only
// measures (Open3D, OpenMP) after every timed case has finished.
//
// Output: a markdown report on stdout; progress on stderr.

#include "acquisition/load_inputs.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/types.h"
#include "io/mesh_file.h"
#include "measure/surface_distance.h"
#include "measure/topology.h"
#include "reconstruct/cube_grid.h"
#include "reconstruct/marching_cubes.h"

#include <CLI/CLI.hpp>
#include <pcl/point_types.h>
#include <pcl/surface/marching_cubes_hoppe.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <type_traits>
#include <unordered_map>
#include <vector>

namespace fs = std::filesystem;
using namespace scan2lod;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// ---------------------------------------------------------------------------
// Plain binary dumps for handing points and meshes between processes.

// T is plain numbers: float/int arrays or Eigen's fixed-size vectors, which
// hold just their coefficients but do not count as trivially copyable.
template <typename T>
void write_array(std::ofstream& out, const std::vector<T>& v) {
  static_assert(std::is_standard_layout_v<T>);
  const std::uint64_t n = v.size();
  out.write(reinterpret_cast<const char*>(&n), sizeof n);
  out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(n * sizeof(T)));
}

template <typename T>
void read_array(std::ifstream& in, std::vector<T>* v) {
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), sizeof n);
  v->resize(n);
  in.read(reinterpret_cast<char*>(v->data()), std::streamsize(n * sizeof(T)));
}

void dump_points(const std::string& path, const OrientedPoints& p) {
  std::ofstream out(path, std::ios::binary);
  write_array(out, p.positions);
  write_array(out, p.normals);
  write_array(out, p.colors);
  write_array(out, p.confidence);
  write_array(out, p.spacing);
  if (!out) throw InputError(path, "could not write the points dump");
}

OrientedPoints undump_points(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  OrientedPoints p;
  read_array(in, &p.positions);
  read_array(in, &p.normals);
  read_array(in, &p.colors);
  read_array(in, &p.confidence);
  read_array(in, &p.spacing);
  if (!in) throw InputError(path, "truncated points dump");
  return p;
}

// Positions and triangles only: normals and colours do not enter any measure.
void dump_mesh(const std::string& path, const TriangleMesh& m) {
  std::ofstream out(path, std::ios::binary);
  write_array(out, m.positions);
  write_array(out, m.triangles);
  if (!out) throw InputError(path, "could not write the mesh dump");
}

TriangleMesh undump_mesh(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  TriangleMesh m;
  read_array(in, &m.positions);
  read_array(in, &m.triangles);
  if (!in) throw InputError(path, "truncated mesh dump");
  return m;
}

// ---------------------------------------------------------------------------
// One case in a forked child.

struct Outcome {
  enum Status { ok, failed, timed_out, crashed } status = failed;
  double seconds = 0;    // as timed by the child
  double peak_mib = 0;   // ru_maxrss of the child, also for killed children
  std::string message;   // why it failed
};

// Fixed size and below PIPE_BUF, so one write() and no blocking before the read.
struct ChildMessage {
  double seconds = 0;
  int ok = 0;
  char error[1024] = {};
};

// Runs `work` (which returns its own timed seconds) in a child; kills it after
// `timeout` seconds if timeout > 0.
Outcome run_in_child(const std::function<double()>& work, double timeout) {
  std::fflush(stdout);
  std::fflush(stderr);
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe() failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork() failed");
  if (pid == 0) {
    close(fds[0]);
    ChildMessage msg;
    try {
      msg.seconds = work();
      msg.ok = 1;
    } catch (const std::exception& e) {
      std::snprintf(msg.error, sizeof msg.error, "%s", e.what());
    }
    [[maybe_unused]] const ssize_t written = write(fds[1], &msg, sizeof msg);
    _exit(0);  // no atexit handlers or static destructors of the parent's state
  }
  close(fds[1]);

  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  rusage usage{};
  bool killed = false;
  for (;;) {
    const pid_t done = wait4(pid, &status, killed ? 0 : WNOHANG, &usage);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) throw std::runtime_error("wait4() failed");
    if (!killed && timeout > 0 && seconds_since(start) > timeout) {
      kill(pid, SIGKILL);
      killed = true;
      continue;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }

  Outcome out;
  out.peak_mib = double(usage.ru_maxrss) / 1024.0;  // KiB on Linux
  ChildMessage msg;
  const ssize_t got = read(fds[0], &msg, sizeof msg);
  close(fds[0]);
  if (killed) {
    out.status = Outcome::timed_out;
    out.seconds = timeout;
    out.message = "killed at the " + std::to_string(int(timeout)) + " s timeout";
  } else if (WIFSIGNALED(status)) {
    out.status = Outcome::crashed;
    out.message = std::string("crashed: ") + strsignal(WTERMSIG(status));
  } else if (got != ssize_t(sizeof msg) || !msg.ok) {
    out.status = Outcome::failed;
    out.message = got == ssize_t(sizeof msg) ? msg.error : "exited without a result";
  } else {
    out.status = Outcome::ok;
    out.seconds = msg.seconds;
  }
  return out;
}

// ---------------------------------------------------------------------------
// The PCL peer.

// PCL's MarchingCubesHoppe on scan2lod's cube grid. PCL spans its grid over the
// points' own box: a different cube size per axis, the surface clipped at the
// data's extremes (the outermost layer of cubes is never polygonised). Its grid
// sample (x, y, z) sits at lower_boundary_ + size_voxel_ * (x, y, z), and
// voxelizeData() is the one virtual step that PCL calls after setting up the
// box and before using it, so the box is replaced there: with resolution R,
// PCL's samples are then scan2lod's corners 0..R-1 on every axis (up to float
// rounding), and its cubes 1..R-2 cover scan2lod's, whose outer four layers
// are padding.
class PclHoppeOnGrid : public pcl::MarchingCubesHoppe<pcl::PointNormal> {
 public:
  explicit PclHoppeOnGrid(const CubeGrid& grid) : grid_(grid) {}

 protected:
  void voxelizeData() override {
    const float h = float(grid_.cube_size);
    this->lower_boundary_ = grid_.origin.cast<float>().array();
    this->upper_boundary_ = this->lower_boundary_ + h * float(grid_.resolution);
    this->size_voxel_ = Eigen::Array3f::Constant(h);
    pcl::MarchingCubesHoppe<pcl::PointNormal>::voxelizeData();
  }

 private:
  CubeGrid grid_;
};

double median(std::vector<double> v) {
  assert(!v.empty());
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// scan2lod leaves a corner undefined when its closest point is farther than
// max_distance * max(cube size, that point's sample spacing). PCL has one
// global threshold, compared against the squared distance: use the same rule
// with the median spacing.
float pcl_ignore_distance(const OrientedPoints& points, double cube_size,
                          const SignedDistanceOptions& distance) {
  double spacing = 0;
  if (!points.spacing.empty()) {
    std::vector<double> s(points.spacing.begin(), points.spacing.end());
    spacing = median(std::move(s));
  }
  const double limit = distance.max_distance * std::max(cube_size, spacing);
  return float(limit * limit);
}

TriangleMesh run_pcl(const OrientedPoints& points, const CubeGrid& grid, float ignore_squared,
                     double* seconds) {
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud(new pcl::PointCloud<pcl::PointNormal>);
  cloud->resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    (*cloud)[i].getVector3fMap() = points.positions[i];
    (*cloud)[i].getNormalVector3fMap() = points.normals[i];
  }
  PclHoppeOnGrid mc(grid);
  mc.setInputCloud(cloud);
  mc.setGridResolution(grid.resolution, grid.resolution, grid.resolution);
  mc.setIsoLevel(0.0f);
  mc.setPercentageExtendGrid(0.0f);  // overridden by PclHoppeOnGrid anyway
  mc.setDistanceIgnore(ignore_squared);

  pcl::PointCloud<pcl::PointNormal> vertices;
  std::vector<pcl::Vertices> polygons;
  const auto start = std::chrono::steady_clock::now();
  mc.reconstruct(vertices, polygons);
  *seconds = seconds_since(start);

  TriangleMesh soup;
  soup.positions.reserve(vertices.size());
  for (const auto& v : vertices) soup.positions.push_back(v.getVector3fMap());
  soup.triangles.reserve(polygons.size());
  for (const auto& poly : polygons)
    soup.triangles.push_back({std::int32_t(poly.vertices[0]), std::int32_t(poly.vertices[1]),
                              std::int32_t(poly.vertices[2])});
  return soup;
}

// ---------------------------------------------------------------------------
// Welding a triangle soup.

TriangleMesh with_vertex_map(const TriangleMesh& soup, const std::vector<std::int32_t>& id,
                             std::vector<Vec3f> positions) {
  TriangleMesh out;
  out.positions = std::move(positions);
  out.triangles.reserve(soup.triangles.size());
  for (const Triangle& t : soup.triangles) out.triangles.push_back({id[t[0]], id[t[1]], id[t[2]]});
  return out;
}

// Merges vertices with bit-identical positions.
TriangleMesh weld_exact(const TriangleMesh& soup) {
  const auto& p = soup.positions;
  std::vector<std::int32_t> order(p.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = std::int32_t(i);
  const auto less = [&](std::int32_t a, std::int32_t b) {
    return std::lexicographical_compare(p[a].data(), p[a].data() + 3, p[b].data(), p[b].data() + 3);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::int32_t> id(p.size());
  std::vector<Vec3f> kept;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || p[order[i]] != p[order[i - 1]]) kept.push_back(p[order[i]]);
    id[order[i]] = std::int32_t(kept.size() - 1);
  }
  return with_vertex_map(soup, id, std::move(kept));
}

// Merges each vertex into the first earlier vertex within `tolerance`. PCL
// computes a shared edge's crossing separately in each cube that has it, from
// corners and directions that round differently, so copies differ in the last
// bits and an exact weld leaves cracks.
TriangleMesh weld_within(const TriangleMesh& soup, float tolerance) {
  struct Cell {
    std::int64_t x, y, z;
    bool operator==(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  struct CellHash {
    std::size_t operator()(const Cell& c) const {
      return std::size_t(c.x * 73856093) ^ std::size_t(c.y * 19349663) ^ std::size_t(c.z * 83492791);
    }
  };
  const auto& p = soup.positions;
  const auto cell_of = [&](const Vec3f& v) {
    return Cell{std::int64_t(std::floor(v.x() / tolerance)), std::int64_t(std::floor(v.y() / tolerance)),
                std::int64_t(std::floor(v.z() / tolerance))};
  };
  // Cell -> first kept vertex in it; further kept vertices of the cell chain via `next`.
  std::unordered_map<Cell, std::int32_t, CellHash> head;
  head.reserve(p.size() / 2);
  std::vector<std::int32_t> next, id(p.size());
  std::vector<Vec3f> kept;
  const float tolerance2 = tolerance * tolerance;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Cell c = cell_of(p[i]);
    std::int32_t found = -1;
    for (int dx = -1; dx <= 1 && found < 0; ++dx)
      for (int dy = -1; dy <= 1 && found < 0; ++dy)
        for (int dz = -1; dz <= 1 && found < 0; ++dz) {
          const auto it = head.find(Cell{c.x + dx, c.y + dy, c.z + dz});
          for (std::int32_t k = it == head.end() ? -1 : it->second; k >= 0; k = next[k])
            if ((kept[k] - p[i]).squaredNorm() <= tolerance2) { found = k; break; }
        }
    if (found < 0) {
      found = std::int32_t(kept.size());
      kept.push_back(p[i]);
      auto [it, inserted] = head.try_emplace(c, found);
      next.push_back(inserted ? -1 : it->second);
      it->second = found;
    }
    id[i] = found;
  }
  return with_vertex_map(soup, id, std::move(kept));
}

// Copies of a PCL vertex differ by float rounding of the coordinates. On the
// bunny at R=128, merging within 0.5 ulp (of the largest coordinate) leaves
// 563 boundary loops, 1 ulp 407, and 2 to 32 ulps all give the same 406;
// what more tolerance adds is only the merging of distinct crossings that
// nearly coincide (near a corner whose value is almost zero), each collapsing
// a sliver: 2 at 2 ulps, 28 at 16. Twice the converged value, then.
float weld_tolerance(const TriangleMesh& soup) {
  float magnitude = 0;
  for (const Vec3f& p : soup.positions) magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
  return 4 * std::numeric_limits<float>::epsilon() * magnitude;
}

// ---------------------------------------------------------------------------
// The report.

struct Row {
  std::string method;
  int resolution = 0;
  std::vector<Outcome> runs;     // empty: skipped
  std::string skipped;           // shown instead of a time when skipped
  std::string mesh_path;         // dump of the first run's output
  bool soup = false;             // PCL: weld before measuring
  const Row* peer = nullptr;     // the PCL row the ratio is taken against
  double cube_size = 0;
  float ignore_squared = 0;      // PCL's setDistanceIgnore

  // measured afterwards in the parent
  std::optional<MeshTopology> topology;
  std::optional<SurfaceComparison> fidelity;
  std::optional<MeshTopology> exact_weld;
  float weld_tolerance = 0;
  std::string measure_error;

  bool all_ok() const {
    if (runs.empty()) return false;
    for (const Outcome& o : runs)
      if (o.status != Outcome::ok) return false;
    return true;
  }
  double seconds() const {
    std::vector<double> s;
    for (const Outcome& o : runs) s.push_back(o.seconds);
    return median(s);
  }
  double peak_mib() const {
    double m = 0;
    for (const Outcome& o : runs) m = std::max(m, o.peak_mib);
    return m;
  }
};

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string time_cell(const Row& r) {
  if (r.runs.empty()) return r.skipped;
  for (const Outcome& o : r.runs)
    if (o.status != Outcome::ok) return o.message;
  std::string cell = fixed(r.seconds(), 2);
  if (r.runs.size() > 1) {  // the spread shows how noisy the machine was
    double lo = r.runs[0].seconds, hi = lo;
    for (const Outcome& o : r.runs) lo = std::min(lo, o.seconds), hi = std::max(hi, o.seconds);
    cell += " (" + fixed(lo, 2) + "–" + fixed(hi, 2) + ", " + std::to_string(r.runs.size()) + " runs)";
  }
  return cell;
}

std::string ratio_cell(const Row& r) {
  if (!r.peer) return r.soup ? "peer" : "—";
  if (!r.all_ok()) return "—";
  const Row& p = *r.peer;
  if (p.runs.empty()) return "— (no peer)";
  if (p.runs[0].status == Outcome::timed_out)  // PCL took at least the timeout
    return "> " + fixed(p.runs[0].seconds / r.seconds(), 1);
  if (!p.all_ok()) return "— (peer failed)";
  return fixed(p.seconds() / r.seconds(), 1);
}

// The source tree's commit, and whether it had uncommitted changes, at run
// time (the binary may be older: run.sh builds nothing); "" without git.
std::string source_revision() {
  const auto run = [](const std::string& command) {
    std::string out;
    if (FILE* f = popen(command.c_str(), "r")) {
      char buf[256];
      while (std::fgets(buf, sizeof buf, f)) out += buf;
      pclose(f);
    }
    return out;
  };
  const std::string git = "git -C '" + std::string(SCAN2LOD_SOURCE_DIR) + "' ";
  std::string head = run(git + "rev-parse --short HEAD 2>/dev/null");
  if (head.empty()) return {};
  head.pop_back();  // newline
  const bool dirty = !run(git + "status --porcelain --untracked-files=no 2>/dev/null").empty();
  return head + (dirty ? " with uncommitted changes" : "");
}

// "1-min 5-min 15-min" load averages from /proc/loadavg.
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

std::string cpu_model() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos)
      return line.substr(line.find(':') + 2);
  return {};
}

void print_report(const std::vector<Row>& rows, const std::string& command_line,
                  const std::string& load_at_start,
                  const std::string& input, const std::string& reference, std::size_t points,
                  double baseline_mib, bool pcl_256, double pcl_timeout) {
  utsname u{};
  uname(&u);
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  const std::string cpu = cpu_model();

  std::printf("# Reconstruction benchmark: scan2lod vs PCL MarchingCubesHoppe\n\n");
  std::printf("%s · %s · nproc %ld%s%s · load average at start %s\n\n", date, u.machine,
              sysconf(_SC_NPROCESSORS_ONLN), cpu.empty() ? "" : " · ", cpu.c_str(),
              load_at_start.c_str());
  std::printf("Command: `%s`  \n", command_line.c_str());
  const std::string revision = source_revision();
  if (!revision.empty()) std::printf("Source: %s (at run time)  \n", revision.c_str());
  std::printf("Input: `%s` (%zu oriented points)  \n", input.c_str(), points);
  std::printf("Reference: %s\n\n", reference.empty() ? "none (fidelity columns empty)"
                                                     : ("`" + reference + "`").c_str());

  std::printf("| method | R | seconds (median) | ratio vs PCL | peak MiB | triangles "
              "| mean %% (out→ref / ref→out) | p95 %% out→ref | components | boundary loops |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows) {
    std::string tris = "—", mean = "—", p95 = "—", comps = "—", loops = "—";
    if (r.topology) {
      tris = std::to_string(r.topology->triangles);
      comps = std::to_string(r.topology->components);
      loops = std::to_string(r.topology->boundary_loops);
    }
    if (r.fidelity) {
      const double d = r.fidelity->diagonal;
      mean = fixed(100 * r.fidelity->a_to_b.mean / d, 3) + " / " +
             fixed(100 * r.fidelity->b_to_a.mean / d, 3);
      p95 = fixed(100 * r.fidelity->a_to_b.p95 / d, 3);
    }
    const bool ran = !r.runs.empty();
    std::printf("| %s | %d | %s | %s | %s | %s | %s | %s | %s | %s |\n", r.method.c_str(),
                r.resolution, time_cell(r).c_str(), ratio_cell(r).c_str(),
                ran ? fixed(r.peak_mib(), 0).c_str() : "—", tris.c_str(), mean.c_str(),
                p95.c_str(), comps.c_str(), loops.c_str());
  }

  std::printf("\nNotes\n\n");
  std::printf("- Every case ran in its own forked process; seconds are wall time of the work "
              "alone, peak MiB is that process's `ru_maxrss`. It includes what the child "
              "inherits from the parent (the loaded points, the libraries it touches): a child "
              "that does nothing peaks at %.0f MiB.\n", baseline_mib);
  std::printf("- scan2lod: `reconstruct()` with default `ReconstructOptions` on all %ld threads; "
              "\"job\" adds `load_oriented_points()` on the input files. "
              "PCL: `MarchingCubesHoppe<PointNormal>` (single-threaded), one run, on the same "
              "positions and normals and on scan2lod's cube grid (same bounding cube and "
              "corners), iso level 0, distance ignore = (`max_distance` · max(cube size, median "
              "spacing))², i.e. scan2lod's undefined-corner rule with one global spacing.\n",
              sysconf(_SC_NPROCESSORS_ONLN));
  std::printf("- scan2lod also drops pieces under 1%% of its triangles and closes small holes "
              "(`min_piece`, `max_hole`); PCL keeps everything its grid produces, which shows in "
              "its components, boundary loops and out→ref error.\n");
  std::printf("- Ratio = PCL seconds / scan2lod seconds at the same R in this run "
              "(the job row against PCL's reconstruction alone).\n");
  if (!pcl_256) std::printf("- PCL at R=256 was skipped (run with `--pcl-256`, about 9 min).\n");
  if (pcl_timeout > 0) std::printf("- PCL cases were killed after %.0f s.\n", pcl_timeout);
  std::printf("- Fidelity: `compare_surfaces` against the reference, distances as %% of the "
              "reference's diagonal; triangles, components and boundary loops from "
              "`mesh_topology`.\n");
  for (const Row& r : rows) {
    if (r.soup && !r.runs.empty())
      std::printf("- PCL R=%d: cube size %.4g m, distance ignore %.4g m².\n", r.resolution,
                  r.cube_size, double(r.ignore_squared));
    if (r.soup && r.topology && r.exact_weld)
      std::printf("- PCL R=%d output is a triangle soup, welded before measuring: vertices within "
                  "%.2g m (4 float ulps of the largest coordinate, %.1e cube sizes) merged, "
                  "%zu triangles collapsed by it. An exact-position weld would leave %zu "
                  "components and %zu boundary loops: copies of a vertex differ in the last "
                  "bits.\n",
                  r.resolution, double(r.weld_tolerance), r.weld_tolerance / r.cube_size,
                  r.topology->degenerate_triangles, r.exact_weld->components,
                  r.exact_weld->boundary_loops);
    if (!r.measure_error.empty())
      std::printf("- %s R=%d: measuring failed: %s\n", r.method.c_str(), r.resolution,
                  r.measure_error.c_str());
  }
}

// The first of `candidates` (relative to the source tree) that exists, or "".
std::string default_path(std::initializer_list<const char*> candidates) {
  for (const char* c : candidates) {
    const fs::path p = fs::path(SCAN2LOD_SOURCE_DIR) / c;
    if (fs::exists(p)) return fs::weakly_canonical(p).string();
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Times scan2lod's reconstruction against PCL's MarchingCubesHoppe; prints a markdown report"};
  // The repository's own bunny if it ships one, else the shared copy beside the checkout.
  std::string input = default_path({"data/bunny/bun.conf", "../shared/data/bunny/data/bun.conf"});
  std::string reference = default_path({"../shared/data/bunny/reconstruction/bun_zipper.ply"});
  bool quick = false, pcl_256 = false;
  double pcl_timeout = 0;
  int runs = 3;
  std::size_t samples = 1000000;
  app.add_option("--input", input, "Scans to reconstruct (.conf, range-grid PLYs, ...)");
  app.add_option("--reference", reference, "Surface to measure fidelity against; empty: none");
  app.add_flag("--quick", quick, "R=64 only, one run each: an end-to-end check in about a minute");
  app.add_flag("--pcl-256", pcl_256, "Also run PCL at R=256 (about 9 minutes)");
  app.add_option("--pcl-timeout", pcl_timeout, "Kill a PCL case after this many seconds (0: never)");
  app.add_option("--runs", runs, "scan2lod runs per case, median reported")->check(CLI::PositiveNumber);
  app.add_option("--samples", samples, "Metro samples per direction for fidelity");
  CLI11_PARSE(app, argc, argv);
  if (input.empty()) {
    std::fprintf(stderr, "no input: neither %s/data/bunny/bun.conf nor ../shared/data/bunny exists; "
                         "pass --input\n", SCAN2LOD_SOURCE_DIR);
    return 2;
  }
  if (quick && app.count("--runs") == 0) runs = 1;
  const std::vector<int> resolutions = quick ? std::vector<int>{64} : std::vector<int>{128, 256};
  const int job_resolution = resolutions.back();
  Progress::set_quiet(true);

  // Other jobs on the machine show up here and in the spread of the runs.
  const std::string load_at_start = load_average();
  std::string command_line = "scan2lod_bench_reconstruct";
  for (int i = 1; i < argc; ++i) command_line += std::string(" ") + argv[i];

  char dir_template[] = "/tmp/scan2lod_bench.XXXXXX";
  if (!mkdtemp(dir_template)) {
    std::perror("mkdtemp");
    return 1;
  }
  const fs::path work_dir(dir_template);
  const auto dump_path = [&](const std::string& name) { return (work_dir / name).string(); };
  const auto log = [](const std::string& what, const Outcome& o) {
    std::fprintf(stderr, "  %-28s %s, peak %.0f MiB\n", what.c_str(),
                 o.status == Outcome::ok ? (fixed(o.seconds, 2) + " s").c_str() : o.message.c_str(),
                 o.peak_mib);
  };

  // Points, loaded in a child (load_oriented_points uses OpenMP).
  std::fprintf(stderr, "loading %s\n", input.c_str());
  const std::string points_dump = dump_path("points.bin");
  const Outcome loaded = run_in_child([&] {
    const auto start = std::chrono::steady_clock::now();
    dump_points(points_dump, load_oriented_points({input}));
    return seconds_since(start);
  }, 0);
  if (loaded.status != Outcome::ok) {
    std::fprintf(stderr, "loading failed: %s\n", loaded.message.c_str());
    fs::remove_all(work_dir);
    return 1;
  }
  const OrientedPoints points = undump_points(points_dump);
  const Aabb box = bounds(points.positions);
  // A child that does nothing: the floor every case's peak includes.
  const double baseline_mib = run_in_child([] { return 0.0; }, 0).peak_mib;
  std::fprintf(stderr, "  %zu points; an idle child peaks at %.0f MiB\n", points.size(), baseline_mib);

  std::vector<Row> rows;
  rows.reserve(2 * resolutions.size() + 1);  // rows point at their peers: no reallocation
  const ReconstructOptions defaults;
  int case_id = 0;
  for (const int R : resolutions) {
    const CubeGrid grid = make_cube_grid(box, R);
    const float ignore = pcl_ignore_distance(points, grid.cube_size, defaults.distance);

    Row pcl;
    pcl.method = "PCL MarchingCubesHoppe";
    pcl.resolution = R;
    pcl.soup = true;
    pcl.cube_size = grid.cube_size;
    pcl.ignore_squared = ignore;
    if (R <= 128 || pcl_256) {
      pcl.mesh_path = dump_path("case" + std::to_string(case_id++) + ".bin");
      std::fprintf(stderr, "PCL R=%d (one run)\n", R);
      pcl.runs.push_back(run_in_child([&] {
        double seconds = 0;
        dump_mesh(pcl.mesh_path, run_pcl(points, grid, ignore, &seconds));
        return seconds;
      }, pcl_timeout));
      log("run 1", pcl.runs.back());
    } else {
      pcl.skipped = "skipped (--pcl-256 to run, ~9 min)";
    }

    Row ours;
    ours.method = "scan2lod reconstruct()";
    ours.resolution = R;
    ours.cube_size = grid.cube_size;
    ours.mesh_path = dump_path("case" + std::to_string(case_id++) + ".bin");
    std::fprintf(stderr, "scan2lod R=%d (%d run%s)\n", R, runs, runs > 1 ? "s" : "");
    for (int run = 0; run < runs; ++run) {
      ours.runs.push_back(run_in_child([&] {
        ReconstructOptions options;
        options.resolution = R;
        const auto start = std::chrono::steady_clock::now();
        const Reconstruction result = reconstruct(points, options);
        const double seconds = seconds_since(start);
        if (run == 0) dump_mesh(ours.mesh_path, result.mesh);
        return seconds;
      }, 0));
      log("run " + std::to_string(run + 1), ours.runs.back());
    }
    rows.push_back(std::move(ours));
    rows.push_back(std::move(pcl));
    rows[rows.size() - 2].peer = &rows.back();
  }

  Row job;
  job.method = "scan2lod job (files → mesh)";
  job.resolution = job_resolution;
  job.mesh_path = dump_path("case" + std::to_string(case_id++) + ".bin");
  for (const Row& r : rows)
    if (r.soup && r.resolution == job_resolution) job.peer = &r;
  std::fprintf(stderr, "scan2lod job R=%d (%d run%s)\n", job_resolution, runs, runs > 1 ? "s" : "");
  for (int run = 0; run < runs; ++run) {
    job.runs.push_back(run_in_child([&] {
      ReconstructOptions options;
      options.resolution = job_resolution;
      const auto start = std::chrono::steady_clock::now();
      const Reconstruction result = reconstruct(load_oriented_points({input}), options);
      const double seconds = seconds_since(start);
      if (run == 0) dump_mesh(job.mesh_path, result.mesh);
      return seconds;
    }, 0));
    log("run " + std::to_string(run + 1), job.runs.back());
  }
  rows.push_back(std::move(job));

  // Measuring, in this process: no more forks from here on.
  std::optional<TriangleMesh> ref;
  if (!reference.empty()) {
    try {
      ref = read_mesh(reference);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "reference unreadable, fidelity skipped: %s\n", e.what());
      reference.clear();
    }
  }
  for (Row& r : rows) {
    if (r.runs.empty() || r.runs[0].status != Outcome::ok) continue;
    std::fprintf(stderr, "measuring %s R=%d\n", r.method.c_str(), r.resolution);
    try {
      TriangleMesh mesh = undump_mesh(r.mesh_path);
      if (r.soup) {
        r.exact_weld = mesh_topology(weld_exact(mesh));
        r.weld_tolerance = weld_tolerance(mesh);
        mesh = weld_within(mesh, r.weld_tolerance);
      }
      r.topology = mesh_topology(mesh);
      if (ref && !mesh.triangles.empty()) {
        CompareOptions options;
        options.samples = samples;
        r.fidelity = compare_surfaces(mesh, *ref, options);
      }
    } catch (const std::exception& e) {
      r.measure_error = e.what();
    }
  }
  fs::remove_all(work_dir);

  print_report(rows, command_line, load_at_start, input, reference, points.size(), baseline_mib,
               pcl_256, pcl_timeout);
  return 0;
}
