#include <scan2lod/reconstruct/brick_reconstruction.h>

#include <scan2lod/core/compact_mesh.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/core/stopwatch.h>
#include <scan2lod/distributed/message.h>
#include <scan2lod/distributed/work_sharing.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/reconstruct/brick_surface.h>
#include <scan2lod/reconstruct/cube_table.h>
#include <scan2lod/reconstruct/hole_filling.h>
#include <scan2lod/reconstruct/point_spool.h>
#include <scan2lod/reconstruct/resolution_guard.h>
#include <scan2lod/reconstruct/signed_distance.h>
#include <scan2lod/reconstruct/welded_surface.h>
#include <scan2lod/spatial/points_near.h>
#include <scan2lod/spatial/point_index.h>

#include <fcntl.h>
#include <malloc.h>
#include <omp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <memory>
#include <unordered_map>
#include <numeric>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;

// Phase 0: the plan's key. Any change of points or options gives another key,
// so a work folder of another build is never taken for this one's.
std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  return h * 0xff51afd7ed558ccdull;
}

template <class T>
std::uint64_t mix_bytes(std::uint64_t h, const std::vector<T>& values) {
  const std::size_t bytes = values.size() * sizeof(T);
  const unsigned char* p = reinterpret_cast<const unsigned char*>(values.data());
  std::size_t i = 0;
  for (; i + 8 <= bytes; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = mix(h, w);
  }
  for (; i < bytes; ++i) h = mix(h, p[i]);
  return mix(h, bytes);
}

std::uint64_t plan_key(const PointCensus& points, const ReconstructOptions& o, int brick_cubes) {
  std::uint64_t h = 0x5332'4c42'524b'0003ull;  // format of the brick files
  // Another release may decide differently: its bricks are not taken.
  for (const char* c = SCAN2LOD_VERSION; *c; ++c) h = mix(h, std::uint64_t(*c));
  h = mix(mix(h, points.hash), points.count);
  h = mix(h, std::uint64_t(points.colors) | std::uint64_t(points.confidence) << 1 | std::uint64_t(points.spacing) << 2);
  const double values[] = {double(o.resolution), double(o.margin), o.reach, double(int(o.distance.method)),
                           double(o.distance.neighbours), o.distance.kernel_width, o.distance.max_distance,
                           double(brick_cubes)};
  for (double v : values) {
    std::uint64_t w;
    std::memcpy(&w, &v, 8);
    h = mix(h, w);
  }
  return h;
}

// The points a brick build reads, in memory or spooled to disk: what they
// are (the census) and a pass over their records.
struct PointSource {
  PointCensus census;
  std::function<void(const RecordVisitor&)> for_each;
  // Under a job whose ranks each spooled a share of the points: the job's
  // ranks (each visits its own share), and the job's index of this share's
  // first point. Null: this process visits every point.
  WorkSharing* shares = nullptr;
  std::size_t first = 0;
};

// How far a point's influence reaches, in world units. A corner is defined
// only within max_distance scales of its closest point p0 (scale: max(cube,
// spacing of p0)), and the planes kernel's weight exp(-(d² - d0²) / σ²) is
// exactly 0 in float past 104 σ², so every point that changes a corner lies
// within sqrt(max_distance² + 105 kernel²) scales of it; reach (2.5 scales)
// is nearer. Vertex colours weigh 8 neighbours at σ = one cube from a
// vertex up to a cube diagonal past a defined corner: four cube diagonals more
// cover that.
double influence_factor(const ReconstructOptions& o) {
  const double d = o.distance.max_distance, k = o.distance.kernel_width;
  return std::max(std::sqrt(d * d + 105.0 * k * k), double(o.reach));
}

// The reach of a point whose scale is `scale`, in world units: its factor of
// scales and the four cube diagonals of the colours.
double influence(double factor, double scale, double cube_size) {
  return factor * scale + 4.0 * std::sqrt(3.0) * cube_size;
}

// The halo every brick gets: margin seeds and the cube-sized part of the influence.
double base_halo(const ReconstructOptions& o, double cube_size) {
  return std::max(influence(influence_factor(o), cube_size, cube_size), (o.margin + 1) * cube_size * std::sqrt(3.0));
}

std::array<int, 3> brick_coords(const CubeGrid& grid, int brick_cubes, int per_axis, const Vec3f& p,
                                const Vec3d& offset) {
  const Vec3d g = ((p.cast<double>() + offset) - grid.origin) / (grid.cube_size * brick_cubes);
  std::array<int, 3> b;
  for (int a = 0; a < 3; ++a) b[a] = std::clamp(int(std::floor(g[a])), 0, per_axis - 1);
  return b;
}

int brick_of(const CubeGrid& grid, int brick_cubes, int per_axis, const Vec3f& p, const Vec3d& offset) {
  const std::array<int, 3> b = brick_coords(grid, brick_cubes, per_axis, p, offset);
  return (b[2] * per_axis + b[1]) * per_axis + b[0];
}

// What the plan reads off the points in one pass: the coarse occupancy
// (the surface's area), points per brick of the smallest size (which nest
// into every larger size, all being powers of two), and a sample of the
// spacings for their median.
struct PointSurvey {
  ReconstructionEstimate whole;  // of every share
  int smallest = 0;                                  // brick side of the counts
  std::vector<std::pair<std::array<int, 3>, std::size_t>> counts;  // brick (at `smallest`), its points
  double median_spacing = 0;

  // Points of the most crowded brick of side B.
  std::size_t largest(int B) const {
    int shift = 0;
    while ((smallest << shift) < B) ++shift;
    std::unordered_map<std::uint64_t, std::size_t> merged;
    std::size_t worst = 0;
    for (const auto& [b, n] : counts) {
      std::size_t& m = merged[pack_key(b[0] >> shift, b[1] >> shift, b[2] >> shift)];
      m += n;
      worst = std::max(worst, m);
    }
    return worst;
  }
};

// What a rank whose plan is not rank 0's is told.
std::string not_rank_zeros_plan(int rank) {
  return "rank " + std::to_string(rank) + " has other reconstruction options or another scan2lod than rank 0: "
         "start every rank with the same command and program";
}

PointSurvey survey(const PointSource& points, const CubeGrid& grid, int smallest, int threads) {
  PointSurvey s;
  s.smallest = smallest;
  const int R = grid.resolution, n = (R + smallest - 1) / smallest;
  CoarseOccupancy occupancy(points.census.box);
  std::unordered_map<std::uint64_t, std::size_t> bins;
  std::uint64_t last = ~std::uint64_t(0);
  std::size_t* last_count = nullptr;
  std::vector<float> spacings;
  // Every so many points of the job, whichever share they are in: the same
  // sample at any number of ranks.
  const std::size_t every = std::max<std::size_t>(1, points.census.count >> 20);
  std::size_t seen = points.first;
  points.for_each([&](const PointRecord* r, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i, ++seen) {
      occupancy.add(r[i].position);
      const std::array<int, 3> c = brick_coords(grid, smallest, n, r[i].position, Vec3d::Zero());
      const std::uint64_t b = pack_key(c[0], c[1], c[2]);
      if (b != last) last = b, last_count = &bins[b];
      ++*last_count;
      if (points.census.spacing && seen % every == 0) spacings.push_back(r[i].spacing);
    }
  });
  if (points.shares) {
    // Every share's counts, occupied cells and spacings, merged alike on every rank.
    MessageWriter out;
    std::vector<std::uint64_t> keys, counts;
    for (const auto& [b, count] : bins) keys.push_back(b), counts.push_back(count);
    out.put(keys), out.put(counts), out.put(occupancy.bits()), out.put(spacings);
    bins.clear(), spacings.clear();
    std::vector<std::uint64_t> bits;
    std::vector<float> theirs;
    for (const std::string& bytes : points.shares->gather_all(out.bytes())) {
      MessageReader in(bytes);
      in.get(&keys), in.get(&counts), in.get(&bits), in.get(&theirs);
      for (std::size_t k = 0; k < keys.size() && k < counts.size(); ++k) bins[keys[k]] += counts[k];
      occupancy.add_bits(bits);
      spacings.insert(spacings.end(), theirs.begin(), theirs.end());
    }
  }
  for (const auto& [b, count] : bins) {
    std::array<int, 3> c;
    unpack_key(b, &c[0], &c[1], &c[2]);
    s.counts.push_back({c, count});
  }
  s.whole = occupancy.estimate(points.census.count, R, threads);
  if (!spacings.empty()) {
    std::nth_element(spacings.begin(), spacings.begin() + spacings.size() / 2, spacings.end());
    s.median_spacing = spacings[spacings.size() / 2];
  }
  return s;
}

// The weld holds the whole surface: leaves, triangles, vertices and their
// keys, then the mesh. The process's peak in the weld (its peak RSS with the
// bricks resumed, or where the bricks peaked lower): 215 MiB for 1.70 M
// estimated cubes (the pair's 16 scans, 1.03 M points, R = 1024), 659 MiB for
// 6.95 M (9.9 M points, R = 2048), at most 2599 MiB for 28.0 M (99 M points,
// R = 4096): 76 MiB and 86-95 bytes a cube. The leaves' hash table holds a
// power of two of 4-byte slots, 2 to 4 a leaf, so a count just past a power
// of two costs some 8 bytes a cube more: 105 here. On disk a cube's share
// takes about 54 bytes (bench/scale: 184 MiB for 3.6 M cubes in 42 bricks,
// 744 MiB for 14.6 M in 194); 60 leaves room.
constexpr double kWeldBaseBytes = 76.0 * (1 << 20);
constexpr double kWeldBytesPerCube = 105.0;
constexpr double kDiskBytesPerCube = 60.0;


// ---- brick files -----------------------------------------------------------

constexpr char kMagic[8] = {'S', '2', 'L', 'B', 'R', 'I', 'C', 'K'};

template <class T>
void put(std::ofstream& out, const std::vector<T>& v) {
  const std::uint64_t n = v.size();
  out.write(reinterpret_cast<const char*>(&n), 8);
  out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(n * sizeof(T)));
}

template <class T>
bool get(std::ifstream& in, std::vector<T>* v, std::uint64_t limit) {
  std::uint64_t n = 0;
  if (!in.read(reinterpret_cast<char*>(&n), 8) || n > limit / sizeof(T)) return false;
  v->resize(n);
  return bool(in.read(reinterpret_cast<char*>(v->data()), std::streamsize(n * sizeof(T))));
}

struct BrickFile {
  std::vector<std::uint64_t> followed;
  BrickSurface surface;
};

// What a finished brick holds, hashed: a brick whose bytes changed on disk is
// run again rather than trusted.
std::uint64_t checksum(const BrickFile& b) {
  const BrickSurface& s = b.surface;
  std::uint64_t h = mix(mix(mix(0, s.cubes_touched), s.corners_evaluated), s.following_rounds);
  h = mix_bytes(h, b.followed);
  h = mix_bytes(h, s.vertex_edges);
  h = mix_bytes(h, s.positions);
  h = mix_bytes(h, s.colors);
  h = mix_bytes(h, s.leaf_cubes);
  h = mix_bytes(h, s.leaf_cases);
  h = mix_bytes(h, s.triangles);
  h = mix_bytes(h, s.requests);
  return mix_bytes(h, s.border_cubes);
}

void write_brick(const std::string& path, std::uint64_t key, const BrickFile& b) {
  write_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out.write(kMagic, 8);
    out.write(reinterpret_cast<const char*>(&key), 8);
    const std::uint64_t counts[3] = {b.surface.cubes_touched, b.surface.corners_evaluated, b.surface.following_rounds};
    out.write(reinterpret_cast<const char*>(counts), sizeof counts);
    put(out, b.followed);
    put(out, b.surface.vertex_edges);
    put(out, b.surface.positions);
    put(out, b.surface.colors);
    put(out, b.surface.leaf_cubes);
    put(out, b.surface.leaf_cases);
    put(out, b.surface.triangles);
    put(out, b.surface.requests);
    put(out, b.surface.border_cubes);
    const std::uint64_t sum = checksum(b);
    out.write(reinterpret_cast<const char*>(&sum), 8);
    out.flush();
    if (!out) throw InputError(tmp, "cannot write the brick: " + std::string(std::strerror(errno)));
  });
}

// A finished brick of this plan, or false (missing, another plan's or
// program's, cut short, or changed).
bool read_brick(const std::string& path, std::uint64_t key, BrickFile* b) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::error_code ec;
  const std::uint64_t size = fs::file_size(path, ec);
  char magic[8];
  std::uint64_t stored = 0, counts[3];
  if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) return false;
  if (!in.read(reinterpret_cast<char*>(&stored), 8) || stored != key) return false;
  if (!in.read(reinterpret_cast<char*>(counts), sizeof counts)) return false;
  BrickSurface& s = b->surface;
  s.cubes_touched = counts[0], s.corners_evaluated = counts[1], s.following_rounds = counts[2];
  if (!get(in, &b->followed, size) || !get(in, &s.vertex_edges, size) || !get(in, &s.positions, size) ||
      !get(in, &s.colors, size) || !get(in, &s.leaf_cubes, size) || !get(in, &s.leaf_cases, size) || !get(in, &s.triangles, size) ||
      !get(in, &s.requests, size) || !get(in, &s.border_cubes, size))
    return false;
  if (s.positions.size() != s.vertex_edges.size() || s.leaf_cubes.size() != s.leaf_cases.size()) return false;
  if (!s.colors.empty() && s.colors.size() != s.positions.size()) return false;
  std::size_t triangles = 0;
  for (std::uint8_t c : s.leaf_cases) triangles += cube_cases()[c].triangle_count;
  if (triangles != s.triangles.size()) return false;
  std::uint64_t sum = 0;
  if (!in.read(reinterpret_cast<char*>(&sum), 8) || sum != checksum(*b)) return false;
  for (const Triangle& t : s.triangles)
    for (std::int32_t v : t)
      if (v < 0 || std::size_t(v) >= s.positions.size()) return false;
  return in.peek() == std::ifstream::traits_type::eof();
}

// ---- phases ----------------------------------------------------------------

// One file of binned points (in the work folder), brick after brick, each
// brick's records in input order.
struct BinFile {
  std::string path;
  int fd = -1;
  bool owner = false;                 // made here, and removed with the bins
  std::vector<std::uint32_t> bricks;  // bricks with points in this file, ascending
  std::vector<std::size_t> first;     // their records run [first[i], first[i + 1]) in the file
};

// The points binned by brick: one file, or one per rank of a job whose
// ranks each binned their share of the points. A brick gathers its points
// and halo from its neighbours' runs, and nothing else of the points is in
// memory.
struct Bins {
  std::vector<BinFile> files;
  std::vector<std::uint32_t> bricks;  // bricks that hold points in any file, ascending
  PointCensus census;                 // of the job's points
  // No point outside this many world units reaches into a brick, under the
  // normal limits and the relaxed ones of hole closing: the base, or more for
  // the bricks that points of wide spacing reach (listed here).
  float base = 0, relaxed_base = 0;
  std::unordered_map<std::uint32_t, std::pair<float, float>> wide;

  Bins() = default;
  Bins(const Bins&) = delete;
  Bins& operator=(const Bins&) = delete;
  ~Bins() {
    for (BinFile& f : files) {
      if (f.fd >= 0) ::close(f.fd);
      std::error_code ec;
      if (f.owner && !f.path.empty()) fs::remove(f.path, ec);
    }
  }
  float far(std::uint32_t brick) const {
    const auto it = wide.find(brick);
    return it == wide.end() ? base : it->second.first;
  }
  float relaxed_far(std::uint32_t brick) const {
    const auto it = wide.find(brick);
    return it == wide.end() ? relaxed_base : it->second.second;
  }
};

// The bins of rank `rank` of a job whose ranks bin shares of the points; -1: of all points.
std::string bins_path(const std::string& work_dir, int rank) {
  const std::string name = rank >= 0 ? "points." + std::to_string(rank) + ".bins" : "points.bins";
  return (fs::path(work_dir) / name).string();
}

// Opens a bin file another rank wrote, checking it holds what that rank said.
void open_bins(BinFile* f, const std::string& rank) {
  const std::string shared = " (every rank must see the work folder at the same path: on several machines, "
                             "a shared file system)";
  f->fd = ::open(f->path.c_str(), O_RDONLY | O_CLOEXEC);
  if (f->fd < 0) throw InputError(f->path, rank + " cannot read the binned points: " + std::strerror(errno) + shared);
  struct stat file {};
  if (::fstat(f->fd, &file) != 0 || std::uint64_t(file.st_size) != f->first.back() * sizeof(PointRecord))
    throw InputError(f->path, rank + " sees another file than the points that were binned there" + shared);
}

// Phase 1: points by the brick they lie in, and each brick's halo: the base,
// or the influence of any point whose influence reaches the brick (a point
// of wide spacing, at a scan's grazing rim, reaches far). Two passes over the
// points: counts (and wide reaches), then records to their brick's run,
// through one small buffer per brick. Under a job whose ranks spooled shares
// of the points, each rank bins its share into a file of its own, and the
// ranks tell each other their files' bricks and the wide reaches.
void bin_points(const PointSource& points, const BrickPlan& plan, const ReconstructOptions& options,
                const std::string& work_dir, Bins* bins) {
  const int n = plan.bricks_per_axis;
  const double h = plan.grid.cube_size;
  ReconstructOptions relaxed = options;
  relaxed.distance.max_distance *= 2.f;
  const double factor = influence_factor(options), relaxed_factor = influence_factor(relaxed);
  bins->census = points.census;
  bins->base = float(plan.halo);
  bins->relaxed_base = float(influence(relaxed_factor, h, h));
  auto brick = [&](const Vec3f& p) {
    return std::uint32_t(brick_of(plan.grid, plan.brick_cubes, n, p, Vec3d::Zero()));
  };
  std::unordered_map<std::uint32_t, std::size_t> counts;
  std::uint32_t last = ~0u;
  std::size_t* last_count = nullptr;  // input order runs along a scan: mostly the same brick as before
  points.for_each([&](const PointRecord* r, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t b = brick(r[i].position);
      if (b != last) last = b, last_count = &counts[b];
      ++*last_count;
      if (!points.census.spacing || r[i].spacing <= h) continue;
      const Vec3f& p = r[i].position;
      const double reach = influence(relaxed_factor, r[i].spacing, h);
      const Vec3d d = Vec3d::Constant(reach);
      const int lo = brick_of(plan.grid, plan.brick_cubes, n, p, -d), hi = brick_of(plan.grid, plan.brick_cubes, n, p, d);
      const float normal = float(influence(factor, r[i].spacing, h));
      for (int z = lo / (n * n); z <= hi / (n * n); ++z)
        for (int y = lo / n % n; y <= hi / n % n; ++y)
          for (int x = lo % n; x <= hi % n; ++x) {
            const auto [it, fresh] =
                bins->wide.try_emplace(std::uint32_t((z * n + y) * n + x), bins->base, bins->relaxed_base);
            it->second.first = std::max(it->second.first, normal);
            it->second.second = std::max(it->second.second, float(reach));
          }
    }
  });
  BinFile& f = bins->files.emplace_back();
  for (const auto& [b, count] : counts) f.bricks.push_back(b);
  std::sort(f.bricks.begin(), f.bricks.end());
  f.first.push_back(0);
  for (std::uint32_t b : f.bricks) f.first.push_back(f.first.back() + counts[b]);

  f.path = bins_path(work_dir, points.shares ? points.shares->rank() : -1);
  f.owner = true;
  f.fd = ::open(f.path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (f.fd < 0) throw InputError(f.path, "cannot write the binned points: " + std::string(std::strerror(errno)));
  // One buffer per brick, 16 MiB in all at most, written out at the brick's cursor when full.
  const std::size_t room = std::clamp<std::size_t>((std::size_t(16) << 20) / sizeof(PointRecord) /
                                                       std::max<std::size_t>(1, f.bricks.size()), 16, 4096);
  std::vector<std::vector<PointRecord>> buffers(f.bricks.size());
  std::vector<std::size_t> cursor(f.first.begin(), f.first.end() - 1);
  auto flush = [&](std::size_t c) {
    std::vector<PointRecord>& buffer = buffers[c];
    const char* bytes = reinterpret_cast<const char*>(buffer.data());
    std::size_t left = buffer.size() * sizeof(PointRecord);
    off_t at = off_t(cursor[c] * sizeof(PointRecord));
    while (left > 0) {
      const ssize_t wrote = ::pwrite(f.fd, bytes, left, at);
      if (wrote < 0 && errno == EINTR) continue;
      if (wrote <= 0) throw InputError(f.path, "cannot write the binned points: " + std::string(std::strerror(errno)));
      bytes += wrote, left -= std::size_t(wrote), at += wrote;
    }
    cursor[c] += buffer.size();
    buffer.clear();
  };
  last = ~0u;
  std::size_t c = 0;
  // A share's records are numbered from its first point's index in the job.
  const std::uint32_t shift = std::uint32_t(points.first);
  points.for_each([&](const PointRecord* r, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t b = brick(r[i].position);
      if (b != last)
        last = b, c = std::size_t(std::lower_bound(f.bricks.begin(), f.bricks.end(), b) - f.bricks.begin());
      if (buffers[c].capacity() == 0) buffers[c].reserve(room);
      buffers[c].push_back(r[i]);
      buffers[c].back().index += shift;
      if (buffers[c].size() == room) flush(c);
    }
  });
  for (std::size_t k = 0; k < buffers.size(); ++k) flush(k);
  if (points.shares) {
    // Flushed before the other ranks open it: a shared file system makes
    // writes visible to other machines when they reach its server.
    if (::fsync(f.fd) != 0) throw InputError(f.path, "cannot flush the binned points: " + std::string(std::strerror(errno)));
    MessageWriter out;
    out.put(f.bricks);
    out.put(std::vector<std::uint64_t>(f.first.begin(), f.first.end()));
    std::vector<std::uint32_t> wide_bricks;
    std::vector<float> wide_reach;  // normal and relaxed, brick after brick
    for (const auto& [b, reach] : bins->wide)
      wide_bricks.push_back(b), wide_reach.push_back(reach.first), wide_reach.push_back(reach.second);
    out.put(wide_bricks), out.put(wide_reach);
    const int me = points.shares->rank();
    const std::vector<std::string> all = points.shares->gather_all(out.bytes());
    BinFile mine = std::move(f);
    bins->files.clear();
    bins->wide.clear();
    for (int r = 0; r < int(all.size()); ++r) {
      if (r == me) {
        bins->files.push_back(std::move(mine));
        mine.fd = -1;
      } else {
        BinFile& theirs = bins->files.emplace_back();
        theirs.path = bins_path(work_dir, r);
        // Rank 0 welds after the others have left: it removes every file.
        theirs.owner = me == 0;
      }
      MessageReader in(all[std::size_t(r)]);
      BinFile& file = bins->files.back();
      std::vector<std::uint64_t> first;
      in.get(&file.bricks), in.get(&first), in.get(&wide_bricks), in.get(&wide_reach);
      file.first.assign(first.begin(), first.end());
      if (wide_reach.size() != 2 * wide_bricks.size()) throw std::runtime_error("a message between ranks is cut short");
      for (std::size_t k = 0; k < wide_bricks.size(); ++k) {
        const auto [it, fresh] = bins->wide.try_emplace(wide_bricks[k], wide_reach[2 * k], wide_reach[2 * k + 1]);
        it->second.first = std::max(it->second.first, wide_reach[2 * k]);
        it->second.second = std::max(it->second.second, wide_reach[2 * k + 1]);
      }
      if (r != me) open_bins(&file, "rank " + std::to_string(me));
    }
    // Only rank 0 removes the files: the others' may be read by it to the end.
    if (me != 0) bins->files[std::size_t(me)].owner = false;
  }
  for (const BinFile& file : bins->files) bins->bricks.insert(bins->bricks.end(), file.bricks.begin(), file.bricks.end());
  std::sort(bins->bricks.begin(), bins->bricks.end());
  bins->bricks.erase(std::unique(bins->bricks.begin(), bins->bricks.end()), bins->bricks.end());
}

// A brick's points with its halo, in their input order: read from its
// neighbours' runs a buffer at a time, and kept when inside (and `near` the
// queries, when given).
OrientedPoints gather(const Bins& bins, const BrickPlan& plan, std::uint32_t brick, double halo,
                      const QueryNeighbourhood* near = nullptr) {
  const int n = plan.bricks_per_axis, B = plan.brick_cubes;
  const int b[3] = {int(brick) % n, int(brick) / n % n, int(brick) / (n * n)};
  const double side = plan.grid.cube_size * B;
  Vec3d lo, hi;
  int from[3], to[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = plan.grid.origin[a] + side * b[a] - halo;
    hi[a] = plan.grid.origin[a] + side * (b[a] + 1) + halo;
    from[a] = std::max(0, int(std::floor((lo[a] - plan.grid.origin[a]) / side)));
    to[a] = std::min(n - 1, int(std::floor((hi[a] - plan.grid.origin[a]) / side)));
  }
  std::vector<PointRecord> kept, buffer(std::size_t(1) << 14);
  for (const BinFile& f : bins.files)
  for (int z = from[2]; z <= to[2]; ++z)
    for (int y = from[1]; y <= to[1]; ++y)
      for (int x = from[0]; x <= to[0]; ++x) {
        const std::uint32_t cell = std::uint32_t((z * n + y) * n + x);
        const auto it = std::lower_bound(f.bricks.begin(), f.bricks.end(), cell);
        if (it == f.bricks.end() || *it != cell) continue;
        const std::size_t c = std::size_t(it - f.bricks.begin());
        for (std::size_t k = f.first[c]; k < f.first[c + 1];) {
          const std::size_t want = std::min(buffer.size(), f.first[c + 1] - k);
          const ssize_t got = ::pread(f.fd, buffer.data(), want * sizeof(PointRecord), off_t(k * sizeof(PointRecord)));
          if (got < 0 && errno == EINTR) continue;
          if (got <= 0 || std::size_t(got) % sizeof(PointRecord) != 0)
            throw InputError(f.path, "cannot read the binned points back: " +
                                         std::string(got < 0 ? std::strerror(errno) : "the file is short"));
          const std::size_t records = std::size_t(got) / sizeof(PointRecord);
          for (std::size_t j = 0; j < records; ++j) {
            const Vec3d p = buffer[j].position.cast<double>();
            if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all() &&
                (!near || near->near(buffer[j].position)))
              kept.push_back(buffer[j]);
          }
          k += records;
        }
      }
  std::sort(kept.begin(), kept.end(), [](const PointRecord& a, const PointRecord& b) { return a.index < b.index; });
  OrientedPoints p;
  p.positions.reserve(kept.size());
  p.normals.reserve(kept.size());
  append_records(kept.data(), kept.size(), bins.census, &p);
  return p;
}

CubeRegion region_of(const BrickPlan& plan, std::uint32_t brick) {
  const int n = plan.bricks_per_axis, b[3] = {int(brick) % n, int(brick) / n % n, int(brick) / (n * n)};
  CubeRegion r;
  for (int a = 0; a < 3; ++a) {
    r.lo[a] = b[a] * plan.brick_cubes;
    r.hi[a] = std::min(plan.grid.resolution, r.lo[a] + plan.brick_cubes);
  }
  return r;
}

std::uint32_t brick_of_cube(const BrickPlan& plan, std::uint64_t cube) {
  int x, y, z;
  unpack_key(cube, &x, &y, &z);
  const int n = plan.bricks_per_axis, B = plan.brick_cubes;
  return std::uint32_t((z / B * n + y / B) * n + x / B);
}

// The brick whose cubes have this lattice point as lower corner (the last
// brick for points on the grid's upper faces).
std::uint32_t brick_of_corner(const BrickPlan& plan, std::uint64_t corner) {
  int xyz[3];
  unpack_key(corner, &xyz[0], &xyz[1], &xyz[2]);
  const int n = plan.bricks_per_axis, B = plan.brick_cubes;
  for (int& c : xyz) c = std::min(c / B, n - 1);
  return std::uint32_t((xyz[2] * n + xyz[1]) * n + xyz[0]);
}

std::string brick_path(const std::string& dir, std::uint32_t brick) {
  char name[32];
  std::snprintf(name, sizeof name, "%08u.brick", brick);
  return (fs::path(dir) / name).string();
}

// Runs work(points) over a brick's points and a halo that starts at
// `halo` and widens to what the work reports it needed (the radius within
// which every point that decided one of its values lies), which then
// suffices. `far`: no point outside reaches farther into the brick. With
// `queries`, only the points within the halo of one of them are gathered:
// those are all a value that holds can depend on. Returns the runs it took.
template <class Work>
std::size_t with_brick_points(const Bins& bins, const BrickPlan& plan, std::uint32_t brick, double halo, double far,
                              Work work, double* widest, const std::vector<Vec3f>* queries = nullptr) {
  for (std::size_t runs = 1;; ++runs) {
    std::optional<QueryNeighbourhood> near;
    if (queries) near.emplace(*queries, halo);
    const OrientedPoints sub = gather(bins, plan, brick, halo, near ? &*near : nullptr);
    *widest = std::max(*widest, halo);
    if (sub.size() == 0 && halo < far) {
      halo = std::min(far, 2 * halo);
      continue;
    }
    const double needed = work(sub);
    if (needed <= halo) return runs;
    halo = needed * (1 + 1e-6);
  }
}


// ---- passes over the bricks, shared by the ranks --------------------------

// What the passes know of a brick: the cubes asked of it, and what its last
// run left for its neighbours and for the weld's room.
struct BrickState {
  std::vector<std::uint64_t> wanted, followed, requests, border;
  std::size_t vertices = 0, leaves = 0, triangles = 0;  // of its share, for the weld's room
  bool colored = false;
  bool pending = false, done = false;
};

// A brick's run (or its finished file, resumed), as every rank learns it
// after the pass.
struct BrickOutcome {
  std::uint32_t brick = 0;
  std::uint64_t vertices = 0, leaves = 0, triangles = 0;
  bool colored = false;
  std::vector<std::uint64_t> followed, requests, border;
};

// Runs a brick with the cubes asked of it, or takes its finished file when
// that one followed them all, and writes it atomically to `dir`.
BrickOutcome run_brick(const Bins& bins, const BrickPlan& plan, const ReconstructOptions& options,
                       const std::string& dir, std::uint32_t brick, const std::vector<std::uint64_t>& wanted,
                       BrickStats* bs) {
  const std::string path = brick_path(dir, brick);
  BrickFile file;
  const bool resumed = read_brick(path, plan.key, &file) &&
                       std::includes(file.followed.begin(), file.followed.end(), wanted.begin(), wanted.end());
  if (resumed) {
    ++bs->bricks_resumed;
  } else {
    // The base halo first; where a value needs more (points of wide
    // spacing nearby), again with what it needs.
    const double cubes_per_point = plan.cubes / double(bins.census.count);
    file.followed = wanted;
    bs->brick_runs += with_brick_points(bins, plan, brick, plan.halo, bins.far(brick),
                                        [&](const OrientedPoints& sub) {
      file.surface = reconstruct_brick(sub, plan.grid, region_of(plan, brick), file.followed,
                                       cubes_per_point * double(sub.size()), bins.far(brick), options);
      return double(file.surface.needed_halo);
    }, &bs->widest_halo);
    write_brick(path, plan.key, file);
  }
  BrickOutcome o;
  o.brick = brick;
  o.vertices = file.surface.vertex_edges.size();
  o.leaves = file.surface.leaf_cubes.size();
  o.triangles = file.surface.triangles.size();
  o.colored = !file.surface.colors.empty();
  o.followed = std::move(file.followed);
  o.requests = std::move(file.surface.requests);
  o.border = std::move(file.surface.border_cubes);
  return o;
}

// Every rank's outcomes of a pass and the sum of their counts, on every rank.
std::vector<BrickOutcome> exchange(WorkSharing& sharing, std::vector<BrickOutcome>&& mine, BrickStats* here) {
  if (sharing.ranks() == 1) return std::move(mine);
  MessageWriter out;
  out.put(std::uint64_t(here->brick_runs));
  out.put(std::uint64_t(here->bricks_resumed));
  out.put(here->widest_halo);
  out.put(std::uint64_t(mine.size()));
  for (const BrickOutcome& o : mine) {
    out.put(o.brick), out.put(o.vertices), out.put(o.leaves), out.put(o.triangles), out.put(std::uint8_t(o.colored));
    out.put(o.followed), out.put(o.requests), out.put(o.border);
  }
  mine.clear();
  *here = BrickStats();
  std::vector<BrickOutcome> all;
  for (const std::string& bytes : sharing.gather_all(out.bytes())) {
    MessageReader in(bytes);
    std::uint64_t runs = 0, resumed = 0, count = 0;
    double widest = 0;
    in.get(&runs), in.get(&resumed), in.get(&widest), in.get(&count);
    here->brick_runs += runs, here->bricks_resumed += resumed, here->widest_halo = std::max(here->widest_halo, widest);
    for (std::uint64_t k = 0; k < count; ++k) {
      BrickOutcome o;
      std::uint8_t colored = 0;
      in.get(&o.brick), in.get(&o.vertices), in.get(&o.leaves), in.get(&o.triangles), in.get(&colored);
      in.get(&o.followed), in.get(&o.requests), in.get(&o.border);
      o.colored = colored != 0;
      all.push_back(std::move(o));
    }
  }
  return all;
}

// Phases 2 and 3: bricks run, and run again with the cubes their neighbours'
// surfaces lead into, until no brick asks another for a cube it lacks. Each
// pass's bricks are shared among the ranks; between passes every rank holds
// the same states, so each decides the next pass alike. Margin seeds reach
// out of a point's own brick, so with a margin every brick whose halo holds
// points runs; else the bricks that hold points.
std::map<std::uint32_t, BrickState> follow_bricks(const Bins& bins, const BrickPlan& plan,
                                                  const ReconstructOptions& options, const std::string& dir,
                                                  WorkSharing& sharing, BrickStats* bs) {
  std::map<std::uint32_t, BrickState> bricks;
  for (std::uint32_t b : bins.bricks) bricks[b].pending = true;
  if (options.margin > 0)
    for (std::uint32_t b : bins.bricks) {
      const int n = plan.bricks_per_axis, r = (options.margin + plan.brick_cubes - 1) / plan.brick_cubes;
      const int x = int(b) % n, y = int(b) / n % n, z = int(b) / (n * n);
      for (int dz = std::max(0, z - r); dz <= std::min(n - 1, z + r); ++dz)
        for (int dy = std::max(0, y - r); dy <= std::min(n - 1, y + r); ++dy)
          for (int dx = std::max(0, x - r); dx <= std::min(n - 1, x + r); ++dx)
            bricks[std::uint32_t((dz * n + dy) * n + dx)].pending = true;
    }
  Progress progress("bricks", bricks.size());
  for (;;) {
    std::vector<std::uint32_t> pending;
    std::vector<char> first;  // the brick's first run: progress
    for (auto& [brick, state] : bricks)
      if (state.pending) state.pending = false, pending.push_back(brick), first.push_back(!state.done);
    if (pending.empty()) break;
    std::vector<BrickOutcome> mine;
    BrickStats here;
    sharing.share(pending.size(), [&](std::size_t i) {
      mine.push_back(run_brick(bins, plan, options, dir, pending[i], bricks.at(pending[i]).wanted, &here));
    }, [&](std::size_t i) {
      if (first[i]) progress.advance();
    });
    for (BrickOutcome& o : exchange(sharing, std::move(mine), &here)) {
      BrickState& state = bricks.at(o.brick);
      state.vertices = o.vertices, state.leaves = o.leaves, state.triangles = o.triangles, state.colored = o.colored;
      state.followed = std::move(o.followed);
      state.requests = std::move(o.requests);
      state.border = std::move(o.border);
      state.done = true;
    }
    bs->brick_runs += here.brick_runs;
    bs->bricks_resumed += here.bricks_resumed;
    bs->widest_halo = std::max(bs->widest_halo, here.widest_halo);
    ++bs->follow_passes;
    // Requests a brick has not met yet make it run again.
    std::vector<std::pair<std::uint32_t, std::uint64_t>> asked;
    for (const auto& [brick, state] : bricks)
      for (std::uint64_t cube : state.requests) asked.push_back({brick_of_cube(plan, cube), cube});
    for (const auto& [target, cube] : asked) {
      BrickState& t = bricks[target];
      if (t.done && (std::binary_search(t.border.begin(), t.border.end(), cube) ||
                     std::binary_search(t.followed.begin(), t.followed.end(), cube)))
        continue;
      if (std::binary_search(t.wanted.begin(), t.wanted.end(), cube)) continue;
      t.wanted.insert(std::upper_bound(t.wanted.begin(), t.wanted.end(), cube), cube);
      t.pending = true;
    }
  }
  progress.finish();
  return bricks;
}

// ---- the plan sent to the other ranks -------------------------------------

constexpr std::uint64_t kPlanMessage = 0x5332'4c42'504c'414eull;  // a plan follows (else: no bricks)

void put_vector(MessageWriter* out, const Vec3d& v) { out->put(v.x()), out->put(v.y()), out->put(v.z()); }
void put_vector(MessageWriter* out, const Vec3f& v) { out->put(v.x()), out->put(v.y()), out->put(v.z()); }
template <class V>
void get_vector(MessageReader* in, V* v) { in->get(&v->x()), in->get(&v->y()), in->get(&v->z()); }

// Rank 0: the plan and the bins' index (the records stay in points.bins,
// which every rank reads from the shared work folder).
void send_plan(WorkSharing& sharing, const BrickPlan& plan, const Bins& bins) {
  // Written before the other ranks open it: flushed for a shared file system
  // that makes writes visible to other machines when they reach its server.
  const BinFile& f = bins.files.front();
  if (::fsync(f.fd) != 0) throw InputError(f.path, "cannot flush the binned points: " + std::string(std::strerror(errno)));
  MessageWriter out;
  out.put(kPlanMessage);
  put_vector(&out, plan.grid.origin);
  out.put(plan.grid.cube_size), out.put(plan.grid.resolution);
  out.put(plan.brick_cubes), out.put(plan.bricks_per_axis), out.put(plan.halo), out.put(plan.cubes);
  out.put(plan.brick_bytes), out.put(plan.weld_bytes), out.put(plan.disk_bytes), out.put(plan.estimated_bytes);
  out.put(plan.median_spacing), out.put(plan.key);
  const PointCensus& c = bins.census;
  out.put(std::uint64_t(c.count));
  put_vector(&out, c.box.min), put_vector(&out, c.box.max);
  out.put(std::uint8_t(c.colors)), out.put(std::uint8_t(c.confidence)), out.put(std::uint8_t(c.spacing)), out.put(c.hash);
  out.put(f.bricks);
  std::vector<std::uint64_t> first(f.first.begin(), f.first.end());
  out.put(first);
  out.put(bins.base), out.put(bins.relaxed_base);
  std::vector<std::pair<std::uint32_t, std::pair<float, float>>> wide(bins.wide.begin(), bins.wide.end());
  out.put(std::uint64_t(wide.size()));
  for (const auto& [brick, reach] : wide) out.put(brick), out.put(reach.first), out.put(reach.second);
  sharing.broadcast(&out.bytes());
}

// Another rank: the plan, or false when rank 0 builds without bricks.
bool receive_plan(WorkSharing& sharing, BrickPlan* plan, Bins* bins) {
  std::string bytes;
  sharing.broadcast(&bytes);
  if (bytes.empty()) return false;
  MessageReader in(bytes);
  std::uint64_t kind = 0, count = 0, wide = 0;
  in.get(&kind);
  if (kind != kPlanMessage) throw std::runtime_error("rank 0 sent no brick plan");
  get_vector(&in, &plan->grid.origin);
  in.get(&plan->grid.cube_size), in.get(&plan->grid.resolution);
  in.get(&plan->brick_cubes), in.get(&plan->bricks_per_axis), in.get(&plan->halo), in.get(&plan->cubes);
  in.get(&plan->brick_bytes), in.get(&plan->weld_bytes), in.get(&plan->disk_bytes), in.get(&plan->estimated_bytes);
  in.get(&plan->median_spacing), in.get(&plan->key);
  PointCensus& c = bins->census;
  std::uint8_t colors = 0, confidence = 0, spacing = 0;
  in.get(&count);
  c.count = std::size_t(count);
  get_vector(&in, &c.box.min), get_vector(&in, &c.box.max);
  in.get(&colors), in.get(&confidence), in.get(&spacing), in.get(&c.hash);
  c.colors = colors, c.confidence = confidence, c.spacing = spacing;
  BinFile& f = bins->files.emplace_back();
  in.get(&f.bricks);
  std::vector<std::uint64_t> first;
  in.get(&first);
  f.first.assign(first.begin(), first.end());
  bins->bricks = f.bricks;
  in.get(&bins->base), in.get(&bins->relaxed_base);
  in.get(&wide);
  for (std::uint64_t k = 0; k < wide; ++k) {
    std::uint32_t brick = 0;
    float normal = 0, relaxed = 0;
    in.get(&brick), in.get(&normal), in.get(&relaxed);
    bins->wide[brick] = {normal, relaxed};
  }
  if (!in.done()) throw std::runtime_error("rank 0's brick plan is longer than expected");
  return true;
}
}  // namespace

namespace {

PointSource source_of(const OrientedPoints& points) {
  return {census_of(points), [&points](const RecordVisitor& visit) { for_each_record(points, visit); }};
}

// A spool of the job's points, or of one share of them (PointSpool::join).
PointSource source_of(const PointSpool& spool, const BrickOptions& bricks) {
  PointSource source{spool.job_census(), [&spool](const RecordVisitor& visit) { spool.for_each(visit); }};
  if (spool.shared()) {
    if (!bricks.sharing) throw std::logic_error("a share of the points without the job's ranks");
    source.shares = bricks.sharing, source.first = spool.first();
  }
  return source;
}

BrickPlan plan_for(const PointSource& points, const ReconstructOptions& options, const BrickOptions& bricks) {
  const std::size_t count = points.census.count;
  if (count == 0) throw InputError("", "no input points: nothing to reconstruct");
  if (count >= (std::size_t(1) << 32)) throw InputError("", "more than 2^32 points in one build: split the input");
  BrickPlan plan;
  plan.grid = make_cube_grid(points.census.box, options.resolution);
  const int R = options.resolution;
  plan.halo = base_halo(options, plan.grid.cube_size);
  const int halo_cubes = int(std::ceil(plan.halo / plan.grid.cube_size));
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  const double budget = bricks.memory_bytes > 0 ? bricks.memory_bytes : machine_memory_bytes();
  const int smallest = std::min(R, std::max(16, 1 << int(std::ceil(std::log2(4.0 * halo_cubes)))));
  const PointSurvey survey_ = survey(points, plan.grid, std::min(smallest, bricks.brick_cubes > 0 ? bricks.brick_cubes : R),
                                     threads);
  const ReconstructionEstimate& whole = survey_.whole;
  auto brick_bytes = [&](int B) {
    const double share = double(survey_.largest(B)) / double(count);
    const double grown = std::pow(double(B + 2 * halo_cubes) / double(B), 2.0);
    return reconstruction_bytes(share * grown * double(count), share * whole.cubes);
  };
  int B = bricks.brick_cubes;
  if (B > 0) {
    if (B & (B - 1) || B < 16) throw InputError("", "brick size " + std::to_string(B) + ": expected a power of two >= 16");
    B = std::min(B, R);
  } else {
    // Brick ids are 32 bits: no more than 2^32 bricks.
    auto countable = [&](int b) { const double n = std::ceil(double(R) / b); return n * n * n < 4294967295.0; };
    for (B = R; B > smallest && countable(B / 2) && brick_bytes(B) > budget; B /= 2) {}
    if (brick_bytes(B) > budget)
      throw InputError("", "--memory " + binary_size(budget) + " is below what one brick needs at resolution " +
                               std::to_string(R) + ": at least " + binary_size(brick_bytes(B)) + " (bricks of " +
                               std::to_string(B) + " cubes, each with a halo of " + std::to_string(halo_cubes) +
                               " cubes)");
  }
  plan.brick_cubes = B;
  plan.bricks_per_axis = (R + B - 1) / B;
  if (double(plan.bricks_per_axis) * plan.bricks_per_axis * plan.bricks_per_axis >= 4294967295.0)
    throw InputError("", "resolution " + std::to_string(R) + " would need about " + binary_size(whole.bytes) +
                             " in core, and more than 2^32 bricks of " + std::to_string(B) +
                             " cubes: choose a coarser --resolution");
  plan.brick_bytes = brick_bytes(B);
  plan.weld_bytes = kWeldBaseBytes + kWeldBytesPerCube * whole.cubes;
  plan.disk_bytes = kDiskBytesPerCube * whole.cubes + double(sizeof(PointRecord)) * double(count);
  plan.cubes = whole.cubes;
  plan.estimated_bytes = whole.bytes;
  plan.median_spacing = survey_.median_spacing;
  plan.key = plan_key(points.census, options, B);
  if (points.shares) {
    // Each rank made the plan: with other options it would not be rank 0's.
    MessageWriter out;
    out.put(plan.key);
    const std::vector<std::string> keys = points.shares->gather_all(out.bytes());
    if (keys.front() != out.bytes())
      throw InputError("", not_rank_zeros_plan(points.shares->rank()));
  }
  return plan;
}

Reconstruction bricks_from(const PointSource& points, const ReconstructOptions& options,
                           const BrickOptions& brick_options, BrickStats* stats_out, const BrickPlan* given_plan) {
  Stopwatch watch;
  auto lap = [&watch] { return watch.lap(); };
  const BrickPlan plan = given_plan ? *given_plan : plan_for(points, options, brick_options);
  Reconstruction result;
  ReconstructStats& stats = result.stats;
  stats.points = points.census.count;
  const std::string advice =
      points.census.spacing
          ? coarse_input_advice(plan.median_spacing, points.census.box.extent().cast<double>().maxCoeff(),
                                options.resolution)
          : "";
  if (!advice.empty()) result.warnings.push_back(advice);

  // Room for the bricks, checked before the work folder is made.
  std::error_code ec;
  fs::path existing = fs::absolute(brick_options.work_dir, ec);
  while (!existing.empty() && !fs::exists(existing, ec) && existing != existing.root_path()) existing = existing.parent_path();
  const fs::space_info space = fs::space(existing, ec);
  if (!ec && double(space.available) < plan.disk_bytes)
    throw InputError(brick_options.work_dir, "resolution " + std::to_string(options.resolution) +
                                                 " would need about " + binary_size(plan.disk_bytes) +
                                                 " of disk for its bricks and " + binary_size(double(space.available)) +
                                                 " are free there");
  const std::string dir = (fs::path(brick_options.work_dir) / "bricks").string();
  // Rank 0 (or this process alone) readies the folder; the ranks that bin
  // shares of the points meet after binning, before any brick is written.
  const bool first_rank = !points.shares || points.shares->rank() == 0;
  if (first_rank) {
    fs::create_directories(dir, ec);
    if (ec) throw InputError(brick_options.work_dir, "cannot make the work folder: " + ec.message());
    // What a killed build was writing: never a finished brick (those are renamed into place).
    for (const auto& entry : fs::directory_iterator(dir, ec))
      if (entry.path().filename().string().rfind(".tmp-", 0) == 0) fs::remove(entry.path(), ec);
  }

  Bins bins;
  bin_points(points, plan, options, brick_options.work_dir, &bins);
  if (brick_options.points_binned) brick_options.points_binned();
  std::unique_ptr<WorkSharing> alone;
  WorkSharing& sharing = brick_options.sharing ? *brick_options.sharing : *(alone = serial_work_sharing());
  if (sharing.ranks() > 1 && !points.shares) send_plan(sharing, plan, bins);

  stats.seconds_index = lap();

  BrickStats bs;
  const std::map<std::uint32_t, BrickState> bricks = follow_bricks(bins, plan, options, dir, sharing, &bs);
  stats.seconds_distances = lap();
  if (!first_rank) return result;  // rank 0 welds

  // Phase 4: the bricks welded by lattice edge, and cleaned up as in core.
  // What the bricks' threads freed goes back to the system first: the
  // weld's arrays, made on this thread, cannot reuse it (at 10^7 points,
  // 456 of the 523 MiB held when the bricks were done; the weld's peak went
  // from 1053 to 923 MiB).
  malloc_trim(0);
  WeldedSurface surface(plan.grid, options.threads);
  {
    std::size_t vertices = 0, leaves = 0, triangles = 0;
    bool colored = false;
    for (const auto& [brick, state] : bricks)
      vertices += state.vertices, leaves += state.leaves, triangles += state.triangles, colored |= state.colored;
    surface.reserve(vertices, leaves, triangles, colored);
  }
  for (const auto& [brick, state] : bricks) {
    BrickFile file;
    if (!read_brick(brick_path(dir, brick), plan.key, &file))
      throw InputError(brick_path(dir, brick), "a finished brick changed or vanished during the build");
    const BrickSurface& s = file.surface;
    surface.add_vertices(s.vertex_edges, s.positions, s.colors);
    surface.add_leaves(s.leaf_cubes, s.leaf_cases, s.triangles);
    stats.cubes_touched += s.cubes_touched;
    stats.corners_evaluated += s.corners_evaluated;
    stats.following_rounds = std::max(stats.following_rounds, s.following_rounds);
  }
  surface.weld();
  stats.cubes_emitting = surface.leaves();
  stats.seconds_emit = lap();

  // Pieces and holes. Corners of cubes grown into holes are evaluated under
  // the relaxed limits by the brick they lie in, with its points.
  ReconstructOptions relaxed = options;
  relaxed.distance.max_distance *= 2.f;
  const float h = float(plan.grid.cube_size);
  const double relaxed_halo = base_halo(relaxed, plan.grid.cube_size);
  auto evaluate = [&](const std::vector<std::uint64_t>& corners, std::vector<float>* values) {
    values->assign(corners.size(), std::numeric_limits<float>::quiet_NaN());
    std::map<std::uint32_t, std::vector<std::size_t>> by_brick;
    for (std::size_t i = 0; i < corners.size(); ++i) by_brick[brick_of_corner(plan, corners[i])].push_back(i);
    for (const auto& [brick, members] : by_brick) {
      std::vector<Vec3f> queries;
      for (std::size_t i : members) {
        int x, y, z;
        unpack_key(corners[i], &x, &y, &z);
        queries.push_back(plan.grid.corner_position(x, y, z));
      }
      with_brick_points(bins, plan, brick, relaxed_halo, bins.relaxed_far(brick),
                        [&](const OrientedPoints& sub) {
        if (sub.size() == 0) return 0.0;
        const PointIndex index(sub);
        std::vector<float> d, needed;
        std::vector<std::int32_t> nearest;
        signed_distances(sub, index, queries, h, relaxed.distance, options.threads, &d, &nearest, nullptr, &needed);
        double widest = 0;
        for (std::size_t j = 0; j < members.size(); ++j) {
          (*values)[members[j]] = d[j];
          widest = std::max(widest, double(std::isnan(d[j]) ? std::min(needed[j], bins.relaxed_far(brick)) : needed[j]));
        }
        return widest;
      }, &bs.widest_halo, &queries);
    }
  };
  stats.triangles_dropped += surface.drop_small_pieces(options.min_piece);
  const std::size_t max_edges = std::size_t(options.max_hole * options.resolution);
  if (options.max_hole > 0.0) {
    for (int round = 0; round < options.hole_rounds; ++round) {
      const std::size_t grown = surface.grow_into_small_holes(max_edges, evaluate);
      if (grown == 0) break;
    }
    surface.give_up_open_growth();
    stats.cubes_hole_closing = surface.grown_cubes();
    stats.triangles_dropped += surface.drop_small_pieces(options.min_piece);
  }
  TriangleMesh& mesh = result.mesh;
  std::vector<std::array<std::int32_t, 2>> boundary;
  std::vector<std::int32_t> grown_vertices;
  surface.finish(&mesh, &boundary, &grown_vertices);
  if (options.max_hole > 0.0) {
    const std::vector<Triangle> patch = fill_small_holes(mesh, boundary, max_edges);
    mesh.triangles.insert(mesh.triangles.end(), patch.begin(), patch.end());
    stats.patch_triangles = patch.size();
  }
  // Colours of the vertices growth added, from the points of their brick.
  if (points.census.colors && !grown_vertices.empty()) {
    std::map<std::uint32_t, std::vector<std::int32_t>> by_brick;
    for (std::int32_t v : grown_vertices)
      by_brick[std::uint32_t(brick_of(plan.grid, plan.brick_cubes, plan.bricks_per_axis, mesh.positions[v],
                                      Vec3d::Zero()))].push_back(v);
    for (const auto& [brick, members] : by_brick) {
      std::vector<Vec3f> at;
      for (std::int32_t v : members) at.push_back(mesh.positions[v]);
      with_brick_points(bins, plan, brick, plan.halo, bins.far(brick), [&](const OrientedPoints& sub) {
        if (sub.size() == 0) return 0.0;
        const PointIndex index(sub);
        std::vector<float> needed;
        const std::vector<Rgb> c = vertex_colors(sub, index, at, h, options.threads, &needed);
        for (std::size_t j = 0; j < members.size(); ++j) mesh.colors[members[j]] = c[j];
        return double(*std::max_element(needed.begin(), needed.end()));
      }, &bs.widest_halo, &at);
    }
  }
  TriangleMesh compact = compact_mesh(mesh.positions, {}, mesh.colors, {&mesh.triangles});
  compact.triangles = std::move(mesh.triangles);
  mesh = std::move(compact);
  stats.seconds_cleanup = lap();
  mesh.normals = vertex_normals(mesh);
  stats.seconds_attributes = lap();
  bs.bricks = bricks.size();
  if (stats_out) *stats_out = bs;
  return result;
}

}  // namespace

BrickPlan plan_bricks(const OrientedPoints& points, const ReconstructOptions& options, const BrickOptions& bricks) {
  return plan_for(source_of(points), options, bricks);
}

BrickPlan plan_bricks(const PointSpool& points, const ReconstructOptions& options, const BrickOptions& bricks) {
  return plan_for(source_of(points, bricks), options, bricks);
}

Reconstruction reconstruct_in_bricks(const OrientedPoints& points, const ReconstructOptions& options,
                                     const BrickOptions& bricks, BrickStats* stats, const BrickPlan* plan) {
  return bricks_from(source_of(points), options, bricks, stats, plan);
}

Reconstruction reconstruct_in_bricks(const PointSpool& points, const ReconstructOptions& options,
                                     const BrickOptions& bricks, BrickStats* stats, const BrickPlan* plan) {
  return bricks_from(source_of(points, bricks), options, bricks, stats, plan);
}

void serve_bricks(const ReconstructOptions& options, const BrickOptions& brick_options) {
  WorkSharing& sharing = *brick_options.sharing;
  BrickPlan plan;
  Bins bins;
  if (!receive_plan(sharing, &plan, &bins)) return;
  const std::string rank = "rank " + std::to_string(sharing.rank());
  if (plan.key != plan_key(bins.census, options, plan.brick_cubes))
    throw InputError("", not_rank_zeros_plan(sharing.rank()));
  BinFile& f = bins.files.front();
  f.path = bins_path(brick_options.work_dir, -1);
  open_bins(&f, rank);
  BrickStats stats;
  follow_bricks(bins, plan, options, (fs::path(brick_options.work_dir) / "bricks").string(), sharing, &stats);
}

void serve_bricks(const PointSpool& share, const ReconstructOptions& options, const BrickOptions& bricks) {
  bricks_from(source_of(share, bricks), options, bricks, nullptr, nullptr);
}

void release_brick_workers(WorkSharing* sharing) {
  if (!sharing || sharing->ranks() == 1 || sharing->rank() != 0) return;
  std::string none;
  sharing->broadcast(&none);
}

}  // namespace scan2lod
