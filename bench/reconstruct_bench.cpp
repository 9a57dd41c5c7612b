// Reconstruction benchmark: scan2lod's sparse marching cubes against the
// reconstructions a user would otherwise reach for, all on the same oriented
// points (positions and normals; the Stanford bunny scans by default):
//   - PCL MarchingCubesHoppe on scan2lod's own cube grid, R = 64, 128 (256
//     with --pcl-256): the same algorithm family on a dense grid;
//   - PCL Poisson and Open3D Poisson (trimmed by density) at depth 8 and 9;
//   - VTK vtkSurfaceReconstructionFilter + vtkContourFilter at 128 samples per
//     side (Hoppe's method; it estimates its own normals from the positions);
// and scaling tables of scan2lod itself at R = 64 ... 512: reconstruct(), and
// the LOD model build after it (build_mc_octree + number_nodes, as `scan2lod
// build` runs them; bench/model_build.h).
//
// What is measured, per case, each in its own forked child process:
//   - seconds: wall time of the library's reconstruction call alone, timed in
//     the child; copying the points into the library's types is outside the
//     timer. A case whose first run takes under --repeat-under seconds is run
//     --runs times (one child each) and the median reported; slower ones run
//     once. Every case is killed after --timeout seconds.
//   - peak MiB: the child's ru_maxrss from wait4(), i.e. its own high-water
//     RSS, also for a child killed at the timeout. It includes what every
//     child inherits from the parent (the loaded points, library pages it
//     touches); the peak of a child that does nothing is printed as the floor.
//   - fidelity: Metro distances (compare_surfaces) between the output and
//     --reference, both directions as % of the reference's diagonal, p95 of
//     output->reference; and the output's triangles, components and boundary
//     loops (mesh_topology). PCL's marching-cubes soup is welded first.
//   - ratio: peer seconds / scan2lod reconstruct() seconds at the comparable
//     resolution, both from this run, because this machine is too noisy for
//     times from different runs to compare.
//
// Comparable settings: marching cubes at R against scan2lod at R; VTK at n
// samples per side against R = n; Poisson at depth d against R = 2^d, whose
// finest cells are 1.1 * extent / 2^d against scan2lod's extent / (R - 8),
// within 7% of each other.
//
// Children get the work by fork() without exec (bench/bench_support.h), so the
// parent must never run OpenMP itself before the last child is done: libgomp's
// thread pool does not survive fork. The parent therefore loads the points in
// a child too and only measures (Open3D, OpenMP) after every timed case has
// finished.
//
// Output: a markdown report on stdout; progress on stderr.

#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/bench/bench_support.h>
#include <scan2lod/bench/library_meshes.h>
#include <scan2lod/bench/model_build.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/core/types.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/cube_grid.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include <CLI/CLI.hpp>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/utility/Logging.h>
#include <pcl/point_types.h>
#include <pcl/surface/marching_cubes_hoppe.h>
#include <pcl/surface/poisson.h>
#include <vtkContourFilter.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSurfaceReconstructionFilter.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

namespace fs = std::filesystem;
using namespace scan2lod;
using namespace scan2lod::bench;

namespace {

// A case's output: positions and triangles (normals and colours do not enter
// any measure) and scan2lod's counters (left default by the peers).
static_assert(std::is_trivially_copyable_v<ReconstructStats>);

void dump_case(const std::string& path, const TriangleMesh& m, const ReconstructStats& stats) {
  std::ofstream out(path, std::ios::binary);
  write_mesh_arrays(out, m);
  out.write(reinterpret_cast<const char*>(&stats), sizeof stats);
  if (!out) throw InputError(path, "could not write the mesh dump");
}

TriangleMesh undump_case(const std::string& path, ReconstructStats* stats) {
  std::ifstream in(path, std::ios::binary);
  TriangleMesh m = read_mesh_arrays(in);
  in.read(reinterpret_cast<char*>(stats), sizeof *stats);
  if (!in) throw InputError(path, "truncated mesh dump");
  return m;
}

// ---------------------------------------------------------------------------
// The peers. Each takes the same oriented points, copies them into its
// library's types (untimed), and sets *seconds to its reconstruction alone.

pcl::PointCloud<pcl::PointNormal>::Ptr to_pcl(const OrientedPoints& points) {
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud(new pcl::PointCloud<pcl::PointNormal>);
  cloud->resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    (*cloud)[i].getVector3fMap() = points.positions[i];
    (*cloud)[i].getNormalVector3fMap() = points.normals[i];
  }
  return cloud;
}

// PCL's triangulated output as an indexed mesh; throws on a non-triangle.
TriangleMesh from_pcl(const pcl::PointCloud<pcl::PointNormal>& vertices,
                      const std::vector<pcl::Vertices>& polygons) {
  TriangleMesh mesh;
  mesh.positions.reserve(vertices.size());
  for (const auto& v : vertices) mesh.positions.push_back(v.getVector3fMap());
  mesh.triangles.reserve(polygons.size());
  for (const auto& poly : polygons) {
    if (poly.vertices.size() != 3)
      throw std::runtime_error("PCL returned a polygon with " +
                               std::to_string(poly.vertices.size()) + " corners, not a triangle");
    mesh.triangles.push_back({std::int32_t(poly.vertices[0]), std::int32_t(poly.vertices[1]),
                              std::int32_t(poly.vertices[2])});
  }
  return mesh;
}

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

// Single-threaded (PCL's marching cubes has no threads). Returns a triangle soup.
TriangleMesh run_pcl_hoppe(const OrientedPoints& points, const CubeGrid& grid,
                           float ignore_squared, double* seconds) {
  PclHoppeOnGrid mc(grid);
  mc.setInputCloud(to_pcl(points));
  mc.setGridResolution(grid.resolution, grid.resolution, grid.resolution);
  mc.setIsoLevel(0.0f);
  mc.setPercentageExtendGrid(0.0f);  // overridden by PclHoppeOnGrid anyway
  mc.setDistanceIgnore(ignore_squared);

  pcl::PointCloud<pcl::PointNormal> vertices;
  std::vector<pcl::Vertices> polygons;
  const auto start = Clock::now();
  mc.reconstruct(vertices, polygons);
  *seconds = seconds_since(start);
  return from_pcl(vertices, polygons);
}

// PCL's Poisson (Kazhdan's PoissonRecon 4, bundled in PCL) with its defaults
// apart from depth, on all cores. It has no density output to trim by, so the
// surface is closed across every hole in the data.
TriangleMesh run_pcl_poisson(const OrientedPoints& points, int depth, double* seconds) {
  pcl::Poisson<pcl::PointNormal> poisson;
  poisson.setInputCloud(to_pcl(points));
  poisson.setDepth(depth);
  poisson.setThreads(0);  // 0: all cores

  pcl::PointCloud<pcl::PointNormal> vertices;
  std::vector<pcl::Vertices> polygons;
  const auto start = Clock::now();
  poisson.reconstruct(vertices, polygons);
  *seconds = seconds_since(start);
  return from_pcl(vertices, polygons);
}

// Open3D's CreateFromPointCloudPoisson (PoissonRecon 12) with its defaults
// apart from depth, on all cores, then the usual trimming: vertices whose
// density (samples supporting them) is below the `trim` quantile are removed
// with their triangles, which cuts away most surface invented across holes.
// The trimming is inside the timer: it is part of the recipe.
TriangleMesh run_open3d_poisson(const OrientedPoints& points, int depth, double trim,
                                double* seconds) {
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  open3d::geometry::PointCloud cloud;
  cloud.points_.reserve(points.size());
  cloud.normals_.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    cloud.points_.push_back(points.positions[i].cast<double>());
    cloud.normals_.push_back(points.normals[i].cast<double>());
  }

  const auto start = Clock::now();
  auto [mesh, density] = open3d::geometry::TriangleMesh::CreateFromPointCloudPoisson(
      cloud, std::size_t(depth));
  if (trim > 0 && !density.empty()) {
    std::vector<double> sorted = density;
    const auto q = sorted.begin() + std::ptrdiff_t(trim * double(sorted.size() - 1));
    std::nth_element(sorted.begin(), q, sorted.end());
    std::vector<bool> low(density.size());
    for (std::size_t i = 0; i < density.size(); ++i) low[i] = density[i] < *q;
    mesh->RemoveVerticesByMask(low);
  }
  *seconds = seconds_since(start);
  return from_open3d(*mesh);
}

// The spacing that gives VTK's grid `samples` samples along the points' longest
// axis: vtkSurfaceReconstructionFilter pads the box by 2 spacings on each side
// and takes floor(padded extent / spacing) samples.
double vtk_sample_spacing(const Aabb& box, int samples) {
  return double(box.extent().maxCoeff()) / (samples - 4 + 0.5);
}

// VTK's vtkSurfaceReconstructionFilter (Hoppe et al. 1992: tangent planes by
// PCA of 20 neighbours, oriented by propagating along a minimum spanning tree;
// the signed distance to the nearest point's plane on a dense grid) and
// vtkContourFilter at 0, single-threaded. It takes positions only: the
// points' normals are not used.
TriangleMesh run_vtk(const OrientedPoints& points, double spacing, double* seconds) {
  vtkNew<vtkPoints> positions;
  positions->SetDataTypeToFloat();
  positions->SetNumberOfPoints(vtkIdType(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i)
    positions->SetPoint(vtkIdType(i), points.positions[i].data());
  vtkNew<vtkPolyData> input;
  input->SetPoints(positions);

  vtkNew<vtkSurfaceReconstructionFilter> distance;
  distance->SetInputData(input);
  distance->SetSampleSpacing(spacing);
  vtkNew<vtkContourFilter> contour;
  contour->SetInputConnection(distance->GetOutputPort());
  contour->SetValue(0, 0.0);
  const auto start = Clock::now();
  contour->Update();
  *seconds = seconds_since(start);
  return from_vtk(contour->GetOutput());
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
// Cases.

// A case's work, run in a child: returns the mesh and sets *seconds to the time
// of the reconstruction alone; scan2lod's cases also fill *stats.
using CaseWork = std::function<TriangleMesh(double* seconds, ReconstructStats* stats)>;

// Method names, as the table shows them.
const std::string kOurs = "scan2lod reconstruct()";
const std::string kJob = "scan2lod job (files → mesh)";
const std::string kPclHoppe = "PCL MarchingCubesHoppe";
const std::string kPclPoisson = "PCL Poisson";
const std::string kOpen3dPoisson = "Open3D Poisson";
const std::string kVtk = "VTK SurfaceReconstruction";

struct Case {
  enum Kind { ours, job, peer };
  Kind kind = peer;
  std::string method;           // e.g. "Open3D Poisson"
  std::string setting;          // e.g. "depth 8"
  int resolution = 0;           // scan2lod's R; for a peer, the R it is compared with
  bool soup = false;            // PCL MarchingCubesHoppe: weld before measuring
  CaseWork work;
  std::vector<Outcome> runs;    // empty: skipped
  std::string skipped;          // shown instead of a time when skipped
  std::string mesh_path;        // dump of the first run's output
  std::string note;             // parameters worth printing under the table

  // measured afterwards in the parent
  ReconstructStats stats;       // scan2lod's counters (ours and job)
  std::optional<MeshTopology> topology;
  std::optional<SurfaceComparison> fidelity;
  std::optional<MeshTopology> exact_weld;
  float weld_tolerance = 0;
  std::string measure_error;

  std::string name() const { return method + " " + setting; }
  bool all_ok() const { return bench::all_ok(runs); }
  double seconds() const { return median_seconds(runs); }
  double peak_mib() const { return bench::peak_mib(runs); }
  // Mean of the two directions' mean distances, % of the reference diagonal.
  std::optional<double> two_sided_mean() const {
    if (!fidelity) return std::nullopt;
    return 100 * 0.5 * (fidelity->a_to_b.mean + fidelity->b_to_a.mean) / fidelity->diagonal;
  }
};

// Runs the case once, and `runs` times in all if the first run took under
// `repeat_under` seconds; each run in its own child, killed after `timeout`
// seconds (0: never). The first run's output is dumped for measuring.
// A run killed at the timeout keeps the timeout as its seconds: a lower bound.
void run_case(Case& c, int runs, double repeat_under, double timeout) {
  std::fprintf(stderr, "%s\n", c.name().c_str());
  c.runs = run_repeated(
      [&](int run) {
        double seconds = 0;
        ReconstructStats stats;
        const TriangleMesh mesh = c.work(&seconds, &stats);
        if (run == 0) dump_case(c.mesh_path, mesh, stats);
        return Values{seconds};
      },
      runs, repeat_under, timeout,
      [](int run, const Outcome& o) {
        std::fprintf(stderr, "  run %-3d %s, peak %.0f MiB\n", run + 1,
                     o.status == Outcome::ok ? (fixed(o.values[0], 2) + " s").c_str() : o.message.c_str(),
                     o.peak_mib);
      });
  for (Outcome& o : c.runs)
    if (o.status == Outcome::timed_out) o.values[0] = timeout;
}

// The scan2lod reconstruct() case at resolution R, or nullptr.
const Case* ours_at(const std::vector<Case>& cases, int resolution) {
  for (const Case& c : cases)
    if (c.kind == Case::ours && c.resolution == resolution) return &c;
  return nullptr;
}

// peer seconds / scan2lod seconds at the peer's comparable resolution; a lower
// bound for a peer killed at the timeout. Empty if either has no time.
std::optional<double> time_ratio(const std::vector<Case>& cases, const Case& peer) {
  const Case* ours = ours_at(cases, peer.resolution);
  if (!ours || !ours->all_ok() || peer.runs.empty()) return std::nullopt;
  if (peer.runs[0].status == Outcome::timed_out) return peer.runs[0].values[0] / ours->seconds();
  if (!peer.all_ok()) return std::nullopt;
  return peer.seconds() / ours->seconds();
}

// ---------------------------------------------------------------------------
// The report.

// The benchmark's options (see main() for their flags).
struct Settings {
  std::string input, reference;
  std::string only;  // run only the cases whose name contains this
  bool quick = false, pcl_256 = false, no_slow = false;
  int runs = 5;  // a short burst of other load then moves the median little
  double repeat_under = 10;
  double timeout = 900;
  double trim = 0.01;
  std::size_t samples = 1000000;
};

// Whether a case's name contains `only`, or one of its '|'-separated parts.
bool name_matches(const std::string& name, const std::string& only) {
  std::size_t at = 0;
  while (true) {
    const std::size_t bar = only.find('|', at);
    if (name.find(only.substr(at, bar == std::string::npos ? std::string::npos : bar - at)) != std::string::npos)
      return true;
    if (bar == std::string::npos) return false;
    at = bar + 1;
  }
}

// Facts about the run the report prints besides the cases.
struct RunInfo {
  std::string command_line, load_at_start, load_at_end;
  std::size_t points = 0;
  double baseline_mib = 0;
  double total_seconds = 0;  // the whole benchmark, loading to measuring
};

std::string time_cell(const Case& c) {
  if (c.runs.empty()) return c.skipped;
  for (const Outcome& o : c.runs)
    if (o.status != Outcome::ok) return o.message;
  std::string cell = fixed(c.seconds(), 2);
  if (c.runs.size() > 1) {  // the spread shows how noisy the machine was
    double lo = c.runs[0].values[0], hi = lo;
    for (const Outcome& o : c.runs) lo = std::min(lo, o.values[0]), hi = std::max(hi, o.values[0]);
    cell += " (" + fixed(lo, 2) + "–" + fixed(hi, 2) + ", " + std::to_string(c.runs.size()) + " runs)";
  } else {
    cell += " (1 run)";
  }
  return cell;
}

std::string ratio_cell(const std::vector<Case>& cases, const Case& c) {
  if (c.kind != Case::peer) return "—";
  const std::optional<double> ratio = time_ratio(cases, c);
  if (!ratio) return "—";
  const bool lower_bound = c.runs[0].status == Outcome::timed_out;
  return (lower_bound ? "> " : "") + fixed(*ratio, 1) + " (R=" + std::to_string(c.resolution) + ")";
}

// "12.3 (×4.1)": a value and its growth from the previous row, if any.
std::string with_growth(double value, std::optional<double> previous, int digits) {
  std::string cell = fixed(value, digits);
  if (previous && *previous > 0) cell += " (×" + fixed(value / *previous, 1) + ")";
  return cell;
}

void print_cases_table(const std::vector<Case>& cases) {
  std::printf("| method | setting | seconds (median) | ratio peer/scan2lod (at R) | peak MiB "
              "| triangles | mean %% (out→ref / ref→out) | two-sided mean %% | p95 %% out→ref "
              "| components | boundary loops |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Case& c : cases) {
    std::string tris = "—", mean = "—", two_sided = "—", p95 = "—", comps = "—", loops = "—";
    if (c.topology) {
      tris = std::to_string(c.topology->triangles);
      comps = std::to_string(c.topology->components);
      loops = std::to_string(c.topology->boundary_loops);
    }
    if (c.fidelity) {
      const double d = c.fidelity->diagonal;
      mean = fixed(100 * c.fidelity->a_to_b.mean / d, 3) + " / " +
             fixed(100 * c.fidelity->b_to_a.mean / d, 3);
      two_sided = fixed(*c.two_sided_mean(), 4);
      p95 = fixed(100 * c.fidelity->a_to_b.p95 / d, 3);
    }
    const std::string method = c.kind == Case::peer ? c.method : "**" + c.method + "**";
    std::printf("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", method.c_str(),
                c.setting.c_str(), time_cell(c).c_str(), ratio_cell(cases, c).c_str(),
                c.runs.empty() ? "—" : fixed(c.peak_mib(), 0).c_str(), tris.c_str(), mean.c_str(),
                two_sided.c_str(), p95.c_str(), comps.c_str(), loops.c_str());
  }
}

// A table over R whose cells show their growth from the row of half the
// resolution: the work should follow the surface's area (×4 per doubling of
// R), not the grid's volume (×8).
struct ScalingColumn {
  std::string title;   // header cell
  std::string growth;  // name in the growth line; empty: a plain value with `suffix`, no growth
  int digits = 0;
  std::string suffix;
};

struct ScalingRow {
  int resolution = 0;
  std::vector<double> values;  // one per column
};

void print_scaling(const std::vector<ScalingColumn>& columns, std::vector<ScalingRow> rows) {
  std::sort(rows.begin(), rows.end(),
            [](const ScalingRow& a, const ScalingRow& b) { return a.resolution < b.resolution; });
  std::printf("| R |");
  for (const ScalingColumn& c : columns) std::printf(" %s |", c.title.c_str());
  std::printf("\n|---:|");
  for (std::size_t k = 0; k < columns.size(); ++k) std::printf("---:|");
  std::printf("\n");
  const auto half = [&](std::size_t i) -> const ScalingRow* {
    return i > 0 && rows[i - 1].resolution * 2 == rows[i].resolution ? &rows[i - 1] : nullptr;
  };
  for (std::size_t i = 0; i < rows.size(); ++i) {
    std::printf("| %d |", rows[i].resolution);
    for (std::size_t k = 0; k < columns.size(); ++k) {
      const double v = rows[i].values[k];
      if (columns[k].growth.empty()) {
        std::printf(" %s%s |", fixed(v, columns[k].digits).c_str(), columns[k].suffix.c_str());
        continue;
      }
      const ScalingRow* h = half(i);
      std::printf(" %s |", with_growth(v, h ? std::optional<double>(h->values[k]) : std::nullopt,
                                       columns[k].digits).c_str());
    }
    std::printf("\n");
  }
  // Geometric mean of the growth per doubling, over all doublings present.
  std::string line;
  for (std::size_t k = 0; k < columns.size(); ++k) {
    if (columns[k].growth.empty()) continue;
    double log_sum = 0;
    int n = 0;
    for (std::size_t i = 0; i < rows.size(); ++i)
      if (const ScalingRow* h = half(i); h && h->values[k] > 0)
        log_sum += std::log(rows[i].values[k] / h->values[k]), ++n;
    line += (line.empty() ? "" : ", ") + columns[k].growth + " ×" +
            (n ? fixed(std::exp(log_sum / n), 2) : std::string("—"));
  }
  std::printf("\nGrowth per doubling of R (in parentheses above; geometric mean over the doublings "
              "here): %s. A dense grid grows ×8 per doubling, a surface ×4.\n", line.c_str());
}

// scan2lod reconstruct() alone over R.
void print_scaling_table(const std::vector<Case>& cases) {
  std::vector<ScalingRow> rows;
  for (const Case& c : cases)
    if (c.kind == Case::ours && c.all_ok() && c.topology)
      rows.push_back({c.resolution,
                      {c.seconds(), c.peak_mib(), double(c.stats.cubes_touched), double(c.stats.corners_evaluated),
                       double(c.topology->triangles),
                       100 * double(c.stats.cubes_touched) / std::pow(double(c.resolution), 3)}});
  if (rows.empty()) {
    std::printf("No scan2lod case completed.\n");
    return;
  }
  print_scaling({{"seconds (median)", "seconds", 2, ""},
                 {"peak MiB", "peak MiB", 0, ""},
                 {"cubes touched", "cubes touched", 0, ""},
                 {"corners evaluated", "corners evaluated", 0, ""},
                 {"triangles", "triangles", 0, ""},
                 {"cubes touched / R³", "", 3, "%"}},
                rows);
}

// The LOD model build over R, one child per run: values are the seconds of
// reconstruct + octree + numbering + clusters, then of each, then the model's
// counts, then the cluster hierarchy's seconds.
struct ModelBuildCase {
  int resolution = 0;
  std::vector<Outcome> runs;  // empty: skipped
  enum Value { total, reconstruct, octree, numbering, nodes, expansions, triangles, clusters };
  double median(Value v) const {
    std::vector<double> x;
    for (const Outcome& o : runs) x.push_back(o.values[v]);
    return bench::median(x);
  }
};

void print_model_scaling_table(const std::vector<ModelBuildCase>& builds) {
  std::vector<ScalingRow> rows;
  for (const ModelBuildCase& b : builds) {
    if (!all_ok(b.runs)) continue;
    using V = ModelBuildCase::Value;
    rows.push_back({b.resolution,
                    {b.median(V::reconstruct), b.median(V::octree) , b.median(V::numbering), b.median(V::clusters),
                     b.median(V::octree) + b.median(V::numbering) + b.median(V::clusters), b.median(V::total),
                     peak_mib(b.runs),
                     b.median(V::nodes), b.median(V::expansions), b.median(V::triangles)}});
  }
  for (const ModelBuildCase& b : builds)
    if (!b.runs.empty() && !all_ok(b.runs))
      for (const Outcome& o : b.runs)
        if (o.status != Outcome::ok) {
          std::printf("R=%d: %s.\n\n", b.resolution, o.message.c_str());
          break;
        }
  if (rows.empty()) {
    std::printf("No model build completed.\n");
    return;
  }
  print_scaling({{"`reconstruct()` s", "reconstruct seconds", 2, ""},
                 {"`build_mc_octree()` s", "octree seconds", 2, ""},
                 {"`number_nodes()` s", "numbering seconds", 2, ""},
                 {"`add_cluster_hierarchy()` s", "cluster seconds", 2, ""},
                 {"**model build** s (octree + numbering + clusters)", "model build seconds", 2, ""},
                 {"points → model s", "points → model seconds", 2, ""},
                 {"peak MiB", "build peak MiB", 0, ""},
                 {"octree nodes", "nodes", 0, ""},
                 {"expansions", "expansions", 0, ""},
                 {"triangles at 100 %", "triangles", 0, ""}},
                rows);
}

// The whole job, files to mesh, against Open3D's Poisson at the comparable
// depth on the same scans (its time excludes reading them), and the share of
// the job that pieces and holes take.
void print_job_summary(const std::vector<Case>& cases) {
  const Case* job = nullptr;
  for (const Case& c : cases)
    if (c.kind == Case::job && c.all_ok()) job = &c;
  if (!job) return;
  const Case* poisson = nullptr;
  for (const Case& c : cases)
    if (c.method == kOpen3dPoisson && c.resolution == job->resolution && c.all_ok()) poisson = &c;
  const ReconstructStats& st = job->stats;
  std::printf("- **Whole job** (files to mesh, `load_oriented_points()` + `reconstruct()`, R=%d): %s s",
              job->resolution, fixed(job->seconds(), 2).c_str());
  if (poisson)
    std::printf(", against %s s for %s on the points of the same scans: scan2lod is **%s× faster**",
                fixed(poisson->seconds(), 2).c_str(), poisson->name().c_str(),
                fixed(poisson->seconds() / job->seconds(), 1).c_str());
  std::printf(". Pieces and holes take %s s of its last run, %s%% of the job (kd-tree %s s, signed distances "
              "%s s, marching cubes %s s; reading the rest).\n",
              fixed(st.seconds_cleanup, 3).c_str(), fixed(100.0 * st.seconds_cleanup / job->seconds(), 1).c_str(),
              fixed(st.seconds_index, 3).c_str(), fixed(st.seconds_distances, 3).c_str(),
              fixed(st.seconds_emit, 3).c_str());
}

// The best peer for time (lowest ratio to scan2lod at its comparable R) and for
// fidelity (lowest two-sided mean), each against scan2lod at that R.
void print_summary(const std::vector<Case>& cases) {
  const Case* fastest = nullptr;
  double fastest_ratio = 0;
  const Case* most_faithful = nullptr;
  for (const Case& c : cases) {
    if (c.kind != Case::peer || !c.all_ok()) continue;
    if (const auto ratio = time_ratio(cases, c); ratio && (!fastest || *ratio < fastest_ratio))
      fastest = &c, fastest_ratio = *ratio;
    const std::optional<double> mean = c.two_sided_mean();
    if (mean && (!most_faithful || *mean < *most_faithful->two_sided_mean())) most_faithful = &c;
  }
  if (fastest) {
    const Case& ours = *ours_at(cases, fastest->resolution);
    const std::string verdict = fastest_ratio >= 1
                                    ? "scan2lod is **" + fixed(fastest_ratio, 1) + "× faster**"
                                    : "the peer is **" + fixed(1 / fastest_ratio, 1) + "× faster**";
    std::printf("- **Time.** The peer closest to scan2lod in speed, at the comparable setting, is "
                "%s: %s s, against %s s for scan2lod at R=%d: %s (ratio %s).\n",
                fastest->name().c_str(), fixed(fastest->seconds(), 2).c_str(),
                fixed(ours.seconds(), 2).c_str(), ours.resolution, verdict.c_str(),
                fixed(fastest_ratio, 2).c_str());
  } else {
    std::printf("- **Time.** No peer completed with a scan2lod case to compare against.\n");
  }
  print_job_summary(cases);
  const Case* ours = most_faithful ? ours_at(cases, most_faithful->resolution) : nullptr;
  if (most_faithful && ours && ours->two_sided_mean()) {
    const double peer = *most_faithful->two_sided_mean(), own = *ours->two_sided_mean();
    std::printf("- **Fidelity** (two-sided mean: the mean of both directions' mean distances, %% "
                "of the reference's diagonal). The most faithful peer is %s at %s%%; scan2lod at "
                "R=%d reaches %s%%, so scan2lod's error is **%s× the peer's** (%s). At that "
                "setting scan2lod takes %s s, the peer %s s.\n",
                most_faithful->name().c_str(), fixed(peer, 4).c_str(), ours->resolution,
                fixed(own, 4).c_str(), fixed(own / peer, 2).c_str(),
                own < peer ? "scan2lod is closer" : own > peer ? "the peer is closer" : "equal",
                fixed(ours->seconds(), 2).c_str(), fixed(most_faithful->seconds(), 2).c_str());
  } else {
    std::printf("- **Fidelity.** No peer was measured against a scan2lod case.\n");
  }
}

void print_notes(const std::vector<Case>& cases, const std::vector<ModelBuildCase>& builds, const Settings& s,
                 const RunInfo& info) {
  std::printf("- Every case ran in its own forked process; seconds are wall time of the "
              "reconstruction call alone, peak MiB is that process's `ru_maxrss`. It includes "
              "what the child inherits from the parent (the loaded points, the libraries it "
              "touches): a child that does nothing peaks at %.0f MiB. %s Cases were killed "
              "after %.0f s.\n",
              info.baseline_mib,
              s.runs == 1 ? "Each case ran once."
                          : ("Cases whose first run took under " + fixed(s.repeat_under, 0) +
                             " s ran " + std::to_string(s.runs) + " times (median, range in "
                             "parentheses); slower ones ran once.").c_str(),
              s.timeout);
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  if (policy && std::string(policy) == "passive")
    std::printf("- OpenMP threads waited passively (`OMP_WAIT_POLICY=passive`, set by "
                "`bench/run.sh`) for every case, scan2lod's included: with libgomp's default "
                "spinning, one other busy process on this 2-core machine made Open3D's Poisson "
                "up to 8× slower.\n");
  std::printf("- Ratio = peer seconds / scan2lod `reconstruct()` seconds at the comparable R, both "
              "from this run: marching cubes at R against R, VTK at n samples per side against "
              "R = n, Poisson at depth d against R = 2^d (finest cells 1.1 · extent / 2^d "
              "against scan2lod's extent / (R − 8), within 7%%).\n");
  std::printf("- scan2lod: `reconstruct()` with default `ReconstructOptions` apart from the "
              "resolution, on all %ld threads; \"job\" adds `load_oriented_points()` on the input "
              "files. It drops pieces under 1%% of its triangles and closes small holes "
              "(`min_piece`, `max_hole`); the bunny's open bottom stays open.\n",
              sysconf(_SC_NPROCESSORS_ONLN));
  if (std::any_of(builds.begin(), builds.end(), [](const ModelBuildCase& b) { return !b.runs.empty(); }))
    std::printf("- LOD model build: as `scan2lod build` makes it (`bench/model_build.h`): `reconstruct()`, "
                "then `build_mc_octree(reconstruction)` (coarse corners signed by the distance to the "
                "finished mesh, its field built inside that call), `number_nodes()` and "
                "`add_cluster_hierarchy()` over the reconstruction's mesh (default `ClusterOptions`, all "
                "cores), each timed; one "
                "child per run, repeated like the cases above when the whole took under %s s. Peak MiB is "
                "that child's, so it includes the reconstruction's.\n",
                fixed(s.repeat_under, 0).c_str());
  // Each peer's parameters, if it ran.
  const auto ran = [&](const std::string& method) {
    return std::any_of(cases.begin(), cases.end(),
                       [&](const Case& c) { return c.method == method && !c.runs.empty(); });
  };
  if (ran(kPclHoppe))
    std::printf("- PCL MarchingCubesHoppe: `MarchingCubesHoppe<PointNormal>` (single-threaded) on "
                "scan2lod's cube grid (same bounding cube and corners), iso level 0, distance "
                "ignore = (`max_distance` · max(cube size, median spacing))², i.e. scan2lod's "
                "undefined-corner rule with one global spacing. It keeps everything its grid "
                "produces, which shows in its components, boundary loops and out→ref error.\n");
  if (ran(kPclPoisson))
    std::printf("- PCL Poisson: `pcl::Poisson<PointNormal>` (PoissonRecon 4) with PCL's "
                "defaults apart from the depth (min depth 5, point weight 4, scale 1.1, samples "
                "per node 1, degree 2, manifold), `setThreads(0)`: all cores. PCL gives no "
                "densities to trim by, so its surface is watertight: it closes the bunny's open "
                "bottom and every hole with invented surface, which shows in out→ref.\n");
  if (ran(kOpen3dPoisson))
    std::printf("- Open3D Poisson: `TriangleMesh::CreateFromPointCloudPoisson(cloud, depth)` "
                "(PoissonRecon 12; width 0, scale 1.1, no linear fit, all threads), then the "
                "vertices whose density is below the %s%% quantile removed with their triangles "
                "(`RemoveVerticesByMask`), timed together. The default, 1%%, is the quantile "
                "of Open3D's own tutorial and, on the bunny at depth 8, the best two-sided mean "
                "of 0, 1, 2, 5 and 10%%: less keeps surface invented across the open bottom "
                "(out→ref grows), more cuts into the real surface (ref→out grows).\n",
                fixed(100 * s.trim, 1).c_str());
  if (ran(kVtk))
    std::printf("- VTK: `vtkSurfaceReconstructionFilter` (neighbourhood 20) with the sample "
                "spacing set for n samples along the longest axis, then `vtkContourFilter` at 0; "
                "single-threaded. It uses the positions only: normals are estimated by VTK (PCA of "
                "20 neighbours, oriented by propagation along a minimum spanning tree), the input "
                "normals are not used. Most of its time goes into that orientation (each step "
                "searches, and each insertion checks, a flat list of candidate points), not "
                "into the grid. Its signed "
                "distance is defined on the whole grid, so the contour can also run where there "
                "is no data.\n");
  std::printf("- Fidelity: `compare_surfaces` against the reference with %zu samples per "
              "direction, distances as %% of the reference's diagonal (two-sided mean: the mean of "
              "both directions' means); triangles, components and "
              "boundary loops from `mesh_topology`. Zero-area triangles (Poisson and VTK outputs "
              "can have some) carry no samples; `mesh_topology` counts them.\n",
              s.samples);
  for (const Case& c : cases) {
    if (!c.note.empty() && !c.runs.empty())
      std::printf("- %s: %s.\n", c.name().c_str(), c.note.c_str());
    if (c.topology && c.topology->degenerate_triangles > 0 && !c.soup)
      std::printf("- %s: %zu degenerate triangles.\n", c.name().c_str(),
                  c.topology->degenerate_triangles);
    if (c.soup && c.topology && c.exact_weld)
      std::printf("- %s output is a triangle soup, welded before measuring: vertices within "
                  "%.2g m (4 float ulps of the largest coordinate) merged, %zu triangles "
                  "collapsed by it. An exact-position weld would leave %zu components and %zu "
                  "boundary loops: copies of a vertex differ in the last bits.\n",
                  c.name().c_str(), double(c.weld_tolerance), c.topology->degenerate_triangles,
                  c.exact_weld->components, c.exact_weld->boundary_loops);
    if (!c.measure_error.empty())
      std::printf("- %s: measuring failed: %s\n", c.name().c_str(), c.measure_error.c_str());
  }
  std::printf("- Whole benchmark: %.0f s wall time.\n", info.total_seconds);
}

void print_report(const std::vector<Case>& cases, const std::vector<ModelBuildCase>& builds, const Settings& s,
                  const RunInfo& info) {
  std::printf("# Reconstruction benchmark: scan2lod against PCL, Open3D and VTK\n\n");
  std::printf("%s\n\n", run_header_line(info.load_at_start, info.load_at_end).c_str());
  std::printf("Command: `%s`  \n", info.command_line.c_str());
  // bench/run.sh makes it passive: see there why.
  std::printf("%s", openmp_line().c_str());
  const std::string revision = source_revision();
  if (!revision.empty()) std::printf("Source: %s (at run time)  \n", revision.c_str());
  std::printf("Input: `%s` (%zu oriented points)  \n", s.input.c_str(), info.points);
  std::printf("Reference: %s\n\n", s.reference.empty() ? "none (fidelity columns empty)"
                                                       : ("`" + s.reference + "`").c_str());

  std::printf("## Every method on the same oriented points\n\n");
  print_cases_table(cases);
  std::printf("\n## Scaling of scan2lod reconstruct()\n\n");
  print_scaling_table(cases);
  std::printf("\n## Scaling of the LOD model build (`scan2lod build`: reconstruct, octree, numbering, clusters)\n\n");
  print_model_scaling_table(builds);
  std::printf("\n## Notes\n\n");
  print_notes(cases, builds, s, info);
  std::printf("\n## Summary: scan2lod against the best peer\n\n");
  print_summary(cases);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Times scan2lod's reconstruction against PCL, Open3D and VTK on the same oriented "
               "points; prints a markdown report"};
  Settings s;
  // The repository's own bunny if it ships one, else the shared copy beside the checkout.
  s.input = default_input();
  s.reference = default_path({"../shared/data/bunny/reconstruction/bun_zipper.ply"});
  app.add_option("--input", s.input, "Scans to reconstruct (.conf, range-grid PLYs, ...)");
  app.add_option("--reference", s.reference, "Surface to measure fidelity against; empty: none");
  app.add_flag("--quick", s.quick,
               "Small settings (R=64 and 128, PCL MC 64, Poisson depth 6), one run each, "
               "implies --no-slow (so no VTK): an end-to-end check in under a minute");
  app.add_flag("--pcl-256", s.pcl_256,
               "Also run PCL MarchingCubesHoppe at R=256 (5 to 9 minutes)");
  app.add_flag("--no-slow", s.no_slow, "Skip every peer expected to take over a minute");
  app.add_option("--runs", s.runs, "Runs of a case under --repeat-under seconds; median reported")
      ->check(CLI::PositiveNumber);
  app.add_option("--repeat-under", s.repeat_under,
                 "Repeat a case only if its first run took under this many seconds");
  app.add_option("--timeout", s.timeout, "Kill a case after this many seconds (0: never)");
  app.add_option("--trim", s.trim, "Open3D Poisson: drop vertices below this density quantile")
      ->check(CLI::Range(0.0, 0.5));
  app.add_option("--samples", s.samples, "Metro samples per direction for fidelity");
  app.add_option("--only", s.only,
                 "Run only the cases whose name (e.g. \"Open3D Poisson depth 8\") contains this, or one of "
                 "several texts separated by '|'; "
                 "the others are listed as skipped");
  CLI11_PARSE(app, argc, argv);
  if (s.input.empty()) {
    std::fprintf(stderr, "no input: neither %s/data/bunny/bun.conf nor ../shared/data/bunny exists; "
                         "pass --input\n", SCAN2LOD_SOURCE_DIR);
    return 2;
  }
  if (s.quick) {
    if (app.count("--runs") == 0) s.runs = 1;
    s.no_slow = true;
  }
  const std::vector<int> resolutions =
      s.quick ? std::vector<int>{64, 128} : std::vector<int>{64, 128, 256, 512};
  const std::vector<int> hoppe_resolutions =
      s.quick ? std::vector<int>{64} : std::vector<int>{64, 128, 256};
  const std::vector<int> poisson_depths = s.quick ? std::vector<int>{6} : std::vector<int>{8, 9};
  const int vtk_samples = s.quick ? 64 : 128;
  const int job_resolution = s.quick ? 64 : ReconstructOptions{}.resolution;
  Progress::set_quiet(true);
  const auto benchmark_start = Clock::now();

  RunInfo info;
  // Other jobs on the machine show up here and in the spread of the runs.
  info.load_at_start = load_average();
  info.command_line = command_line("scan2lod_bench_reconstruct", argc, argv);

  const ScratchDir work_dir("scan2lod_reconstruct_bench");

  std::fprintf(stderr, "loading %s\n", s.input.c_str());
  OrientedPoints points;
  try {
    points = load_points_in_child(s.input, work_dir.path("points.bin"));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "loading failed: %s\n", e.what());
    return 1;
  }
  const Aabb box = bounds(points.positions);
  info.points = points.size();
  // A child that does nothing: the floor every case's peak includes.
  info.baseline_mib = run_in_child([] { return Values{}; }, 0).peak_mib;
  std::fprintf(stderr, "  %zu points; an idle child peaks at %.0f MiB\n", points.size(),
               info.baseline_mib);

  std::vector<Case> cases;
  const auto add = [&](Case c) {
    c.mesh_path = work_dir.path("case" + std::to_string(cases.size()) + ".bin");
    cases.push_back(std::move(c));
  };
  // `expected` is the peer's time on the bunny on the 2-core machine this
  // benchmark was written on, without other load; --no-slow skips those over
  // a minute.
  const auto add_peer = [&](Case c, double expected) {
    if (c.skipped.empty() && s.no_slow && expected > 60)
      c.skipped = "skipped (--no-slow; ~" + fixed(expected, 0) + " s)";
    add(std::move(c));
  };

  for (const int R : resolutions) {
    Case c;
    c.kind = Case::ours;
    c.method = kOurs;
    c.setting = "R=" + std::to_string(R);
    c.resolution = R;
    c.work = [&points, R](double* seconds, ReconstructStats* stats) {
      ReconstructOptions options;
      options.resolution = R;
      const auto start = Clock::now();
      Reconstruction result = reconstruct(points, options);
      *seconds = seconds_since(start);
      *stats = result.stats;
      return std::move(result.mesh);
    };
    add(std::move(c));
  }
  for (const int R : hoppe_resolutions) {
    const CubeGrid grid = make_cube_grid(box, R);
    const float ignore = pcl_ignore_distance(points, grid.cube_size, ReconstructOptions{}.distance);
    Case c;
    c.method = kPclHoppe;
    c.setting = "R=" + std::to_string(R);
    c.resolution = R;
    c.soup = true;
    c.note = "cube size " + fixed(grid.cube_size * 1e3, 3) + " mm, distance ignore " +
             fixed(std::sqrt(ignore) * 1e3, 3) + " mm (squared: " + fixed(ignore * 1e6, 3) + " mm²)";
    c.work = [&points, grid, ignore](double* seconds, ReconstructStats*) {
      return run_pcl_hoppe(points, grid, ignore, seconds);
    };
    if (R > 128 && !s.pcl_256) c.skipped = "skipped (--pcl-256 to run, 5–9 min)";
    // Dense grid: R^3 corners, one kd-tree query each.
    add_peer(std::move(c), R <= 64 ? 6 : R <= 128 ? 44 : 320 * std::pow(R / 256.0, 3));
  }
  for (const int depth : poisson_depths) {
    Case pcl_case;
    pcl_case.method = kPclPoisson;
    pcl_case.setting = "depth " + std::to_string(depth);
    pcl_case.resolution = 1 << depth;
    pcl_case.work = [&points, depth](double* seconds, ReconstructStats*) {
      return run_pcl_poisson(points, depth, seconds);
    };
    add_peer(std::move(pcl_case), depth <= 8 ? 13 : 25 * std::pow(4, depth - 9));

    Case o3d;
    o3d.method = kOpen3dPoisson;
    o3d.setting = "depth " + std::to_string(depth);
    o3d.resolution = 1 << depth;
    const double trim = s.trim;
    o3d.work = [&points, depth, trim](double* seconds, ReconstructStats*) {
      return run_open3d_poisson(points, depth, trim, seconds);
    };
    add_peer(std::move(o3d), depth <= 8 ? 5 : 30 * std::pow(4, depth - 9));
  }
  {
    const double spacing = vtk_sample_spacing(box, vtk_samples);
    Case c;
    c.method = kVtk;
    c.setting = std::to_string(vtk_samples) + " samples/side";
    c.resolution = vtk_samples;
    const Vec3d padded = box.extent().cast<double>() + Vec3d::Constant(4 * spacing);
    c.note = "sample spacing " + fixed(spacing * 1e3, 3) + " mm, grid " +
             std::to_string(int(padded.x() / spacing)) + "×" + std::to_string(int(padded.y() / spacing)) +
             "×" + std::to_string(int(padded.z() / spacing));
    c.work = [&points, spacing](double* seconds, ReconstructStats*) {
      return run_vtk(points, spacing, seconds);
    };
    // Mostly orienting the normals, whatever the grid: 215 s at 64, 300 s at 128.
    add_peer(std::move(c), 300);
  }
  {
    Case c;
    c.kind = Case::job;
    c.method = kJob;
    c.setting = "R=" + std::to_string(job_resolution);
    c.resolution = job_resolution;
    const std::string input = s.input;
    c.work = [input, job_resolution](double* seconds, ReconstructStats* stats) {
      ReconstructOptions options;
      options.resolution = job_resolution;
      const auto start = Clock::now();
      Reconstruction result = reconstruct(load_oriented_points({input}), options);
      *seconds = seconds_since(start);
      *stats = result.stats;
      return std::move(result.mesh);
    };
    add(std::move(c));
  }
  // Report order: by comparable R, scan2lod first in each group, the job last.
  std::stable_sort(cases.begin(), cases.end(), [](const Case& a, const Case& b) {
    const auto key = [](const Case& c) {
      return std::make_tuple(c.kind == Case::job, c.resolution, c.kind != Case::ours);
    };
    return key(a) < key(b);
  });

  for (Case& c : cases) {
    if (c.skipped.empty() && !name_matches(c.name(), s.only)) c.skipped = "skipped (--only)";
    if (c.skipped.empty()) run_case(c, s.runs, s.repeat_under, s.timeout);
    else std::fprintf(stderr, "%s: %s\n", c.name().c_str(), c.skipped.c_str());
  }

  // The LOD model build at every R, for its scaling.
  std::vector<ModelBuildCase> builds;
  for (const int R : resolutions) {
    ModelBuildCase b;
    b.resolution = R;
    const std::string name = "scan2lod model build R=" + std::to_string(R);
    if (!name_matches(name, s.only)) {
      std::fprintf(stderr, "%s: skipped (--only)\n", name.c_str());
      builds.push_back(std::move(b));
      continue;
    }
    std::fprintf(stderr, "%s\n", name.c_str());
    b.runs = run_repeated(
        [&](int) {
          const TimedModel t = build_model_timed(points, R);
          return Values{t.reconstruct_seconds + t.model_seconds(), t.reconstruct_seconds, t.octree_seconds,
                        t.numbering_seconds, double(t.model.octree->tree.size()), double(t.model.octree->lod.full()),
                        double(t.full_triangles), t.cluster_seconds};
        },
        s.runs, s.repeat_under, s.timeout,
        [](int run, const Outcome& o) {
          std::fprintf(stderr, "  run %-3d %s, peak %.0f MiB\n", run + 1,
                       o.status == Outcome::ok
                           ? format("reconstruct %.2f s, octree %.2f s, numbering %.2f s, clusters %.2f s",
                                    o.values[1], o.values[2], o.values[3], o.values[7]).c_str()
                           : o.message.c_str(),
                       o.peak_mib);
        });
    builds.push_back(std::move(b));
  }

  info.load_at_end = load_average();

  // Measuring, in this process: no more forks from here on.
  std::optional<TriangleMesh> ref;
  if (!s.reference.empty()) {
    try {
      ref = read_mesh(s.reference);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "reference unreadable, fidelity skipped: %s\n", e.what());
      s.reference.clear();
    }
  }
  for (Case& c : cases) {
    if (c.runs.empty() || c.runs[0].status != Outcome::ok) continue;
    std::fprintf(stderr, "measuring %s\n", c.name().c_str());
    try {
      TriangleMesh mesh = undump_case(c.mesh_path, &c.stats);
      if (c.soup) {
        c.exact_weld = mesh_topology(weld_exact(mesh));
        c.weld_tolerance = weld_tolerance(mesh);
        mesh = weld_within(mesh, c.weld_tolerance);
      }
      c.topology = mesh_topology(mesh);
      if (ref && !mesh.triangles.empty()) {
        CompareOptions options;
        options.samples = s.samples;
        c.fidelity = compare_surfaces(mesh, *ref, options);
      }
    } catch (const std::exception& e) {
      c.measure_error = e.what();
    }
  }
  info.total_seconds = seconds_since(benchmark_start);
  print_report(cases, builds, s, info);
  return 0;
}
