#include <scan2lod/reconstruct/resolution_guard.h>

#include <scan2lod/core/error.h>
#include <scan2lod/reconstruct/cube_grid.h>

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace scan2lod {
namespace {

// Measured on the bunny scans (bench/REPORT.md, reconstruct() at R = 64 ... 512):
// cubes touched per cube of surface found at the coarse grid, and the peak memory
// and time per touched cube and per point.
constexpr double kCubesPerCoarseCell = 1.1;
constexpr double kBytesPerCube = 700.0;
constexpr double kBytesPerPoint = 120.0;  // positions, normals, spacing, kd-tree
constexpr double kFixedBytes = 48.0 * 1024 * 1024;
constexpr double kCoreSecondsPerCube = 12e-6;
constexpr double kCoreSecondsPerPoint = 1.5e-6;

std::string gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, bytes >= 1e9 ? "%.1f GB" : "%.0f MB", bytes >= 1e9 ? bytes / 1e9 : bytes / 1e6);
  return text;
}

std::string duration(double seconds) {
  char text[32];
  if (seconds < 120) std::snprintf(text, sizeof text, "%.0f s", std::max(1.0, seconds));
  else if (seconds < 7200) std::snprintf(text, sizeof text, "%.0f min", seconds / 60);
  else std::snprintf(text, sizeof text, "%.0f h", seconds / 3600);
  return text;
}

double cgroup_limit() {
  for (const char* path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(path);
    double value;
    if (in >> value && value > 0) return value;  // "max" fails to parse: no limit
  }
  return 0;
}

}  // namespace

double reconstruction_bytes(double points, double cubes) {
  return kFixedBytes + kBytesPerPoint * points + kBytesPerCube * cubes;
}

CoarseOccupancy::CoarseOccupancy(const Aabb& box) {
  for (int coarse = 64; coarse >= kMinResolution; coarse /= 2) {
    Level level;
    level.grid = make_cube_grid(box, coarse);
    level.bits.assign((std::size_t(coarse) * coarse * coarse + 63) / 64, 0);
    levels_.push_back(std::move(level));
  }
}

void CoarseOccupancy::add(const Vec3f& p) {
  for (Level& level : levels_) {
    const int R = level.grid.resolution;
    const Vec3d g = (p.cast<double>() - level.grid.origin) / level.grid.cube_size;
    std::size_t c[3];
    for (int a = 0; a < 3; ++a) c[a] = std::size_t(std::clamp(int(std::floor(g[a])), 0, R - 1));
    const std::size_t cell = (c[2] * R + c[1]) * R + c[0];
    std::uint64_t& word = level.bits[cell / 64];
    const std::uint64_t bit = std::uint64_t(1) << (cell % 64);
    level.cells += (word & bit) == 0;
    word |= bit;
  }
}

std::vector<std::uint64_t> CoarseOccupancy::bits() const {
  std::vector<std::uint64_t> all;
  for (const Level& level : levels_) all.insert(all.end(), level.bits.begin(), level.bits.end());
  return all;
}

void CoarseOccupancy::add_bits(const std::vector<std::uint64_t>& bits) {
  std::size_t at = 0;
  for (const Level& level : levels_) at += level.bits.size();
  if (bits.size() != at) throw std::invalid_argument("occupancy bits of another grid");
  at = 0;
  for (Level& level : levels_) {
    level.cells = 0;
    for (std::uint64_t& word : level.bits) {
      word |= bits[at++];
      level.cells += std::size_t(__builtin_popcountll(word));
    }
  }
}

ReconstructionEstimate CoarseOccupancy::estimate(std::size_t points, int resolution, int threads) const {
  ReconstructionEstimate e;
  e.resolution = resolution;
  if (points == 0) return e;
  // The coarse grid must be sampled densely enough to show the whole surface:
  // a few points per occupied cell, else a coarser one.
  std::size_t l = 0;
  while (l + 1 < levels_.size() && double(points) < 4.0 * double(levels_[l].cells)) ++l;
  const double scale = double(resolution - 8) / double(levels_[l].grid.resolution - 8);
  e.cubes = kCubesPerCoarseCell * double(levels_[l].cells) * scale * scale;
  const double n = double(points);
  e.bytes = reconstruction_bytes(n, e.cubes);
  const int cores = threads > 0 ? threads : omp_get_max_threads();
  e.seconds = (kCoreSecondsPerCube * e.cubes + kCoreSecondsPerPoint * n) / std::max(1, cores);
  return e;
}

ReconstructionEstimate estimate_reconstruction(const OrientedPoints& points, int resolution, int threads) {
  if (points.size() == 0) return ReconstructionEstimate{resolution};
  CoarseOccupancy occupancy(bounds(points.positions));
  for (const Vec3f& p : points.positions) occupancy.add(p);
  return occupancy.estimate(points.size(), resolution, threads);
}

double machine_memory_bytes() {
  const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
  const double limit = cgroup_limit();
  return limit > 0 && limit < physical ? limit : physical;
}

std::string binary_size(double bytes) {
  if (bytes >= 10.0 * (1 << 30)) return std::to_string(std::llround(bytes / (1 << 30))) + " GiB";
  return std::to_string(std::llround(bytes / (1 << 20))) + " MiB";
}

double available_memory_bytes() {
  double available = machine_memory_bytes();
  std::ifstream meminfo("/proc/meminfo");
  std::string name;
  double kib;
  while (meminfo >> name >> kib) {
    if (name == "MemAvailable:") available = std::min(available, kib * 1024.0);
    meminfo.ignore(64, '\n');
  }
  const double limit = cgroup_limit();
  std::ifstream usage("/sys/fs/cgroup/memory.current");
  double used;
  if (limit > 0 && usage >> used) available = std::min(available, limit - used);
  return 0.9 * std::max(available, 0.0);
}

ReconstructionEstimate check_resolution_fits(const OrientedPoints& points, int resolution, int threads,
                                             double memory_bytes) {
  if (memory_bytes <= 0) memory_bytes = machine_memory_bytes();
  const ReconstructionEstimate e = estimate_reconstruction(points, resolution, threads);
  if (e.bytes <= memory_bytes) return e;
  int fits = resolution;
  while (fits > kMinResolution && estimate_reconstruction(points, fits, threads).bytes > memory_bytes) fits /= 2;
  const bool any = estimate_reconstruction(points, fits, threads).bytes <= memory_bytes;
  throw InputError("", "resolution " + std::to_string(resolution) + " would need about " + gigabytes(e.bytes) +
                           " of memory (" + std::to_string(std::llround(e.cubes / 1e6)) + " M cubes over the surface, " +
                           duration(e.seconds) + ") and this machine has " + gigabytes(memory_bytes) +
                           (any ? "; the largest resolution that fits is " + std::to_string(fits) +
                                      " (about " + gigabytes(estimate_reconstruction(points, fits, threads).bytes) + ")"
                                : "; not even resolution " + std::to_string(kMinResolution) + " fits"));
}

std::string coarse_input_advice(const OrientedPoints& points, int resolution) {
  if (points.spacing.size() != points.size() || points.size() == 0) return "";
  std::vector<float> spacing = points.spacing;
  std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
  return coarse_input_advice(spacing[spacing.size() / 2], bounds(points.positions).extent().cast<double>().maxCoeff(),
                             resolution);
}

std::string coarse_input_advice(double median, double extent, int resolution) {
  const double cube = extent / double(resolution - 8);
  // Vertices more than 4 cubes apart: the cubes between them only re-sample flat triangles.
  if (!(median > 4.0 * cube)) return "";
  int suggested = kMinResolution;
  while (suggested < resolution && extent / double(2 * suggested - 8) >= median) suggested *= 2;
  suggested = std::min(resolution, 2 * suggested);  // cubes of half to one vertex spacing
  char text[320];
  std::snprintf(text, sizeof text,
                "the input's points lie %.1f cubes apart (median spacing %.3g against cube size %.3g at "
                "resolution %d): the grid fills the surface between them with many more triangles "
                "without adding detail; --resolution %d matches the point spacing",
                median / cube, median, cube, resolution, suggested);
  return text;
}

}  // namespace scan2lod
