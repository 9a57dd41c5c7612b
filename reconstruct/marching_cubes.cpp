#include "reconstruct/marching_cubes.h"

#include "core/error.h"
#include "core/flat_hash.h"
#include "core/progress.h"
#include "reconstruct/cube_table.h"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace scan2lod {
namespace {

constexpr std::uint64_t kAxisStep[3] = {1ull, 1ull << 20, 1ull << 40};

std::uint64_t corner_key_of(std::uint64_t cube_key, int corner) {
  return cube_key + (corner & 1) * kAxisStep[0] + ((corner >> 1) & 1) * kAxisStep[1] +
         ((corner >> 2) & 1) * kAxisStep[2];
}

// The sparse grid under construction: touched cubes, and the corners they share.
struct SparseGrid {
  FlatHashMap cube_index;
  std::vector<std::uint64_t> cube_keys;
  std::vector<std::array<std::int32_t, 8>> cube_corners;
  FlatHashMap corner_index;
  std::vector<std::uint64_t> corner_keys;
  std::vector<float> corner_distances;
  std::vector<std::int32_t> corner_nearest;

  bool add_cube(std::uint64_t key) {
    std::int32_t id = std::int32_t(cube_keys.size());
    if (cube_index.insert(key, id) != id) return false;
    cube_keys.push_back(key);
    return true;
  }
};

void check_points(const OrientedPoints& points) {
  if (points.size() == 0) throw InputError("", "no input points: nothing to reconstruct");
  if (points.normals.size() != points.size())
    throw InputError("", "input points lack normals");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points.positions[i].allFinite())
      throw InputError("", "input point " + std::to_string(i) + " has non-finite coordinates");
    if (!points.normals[i].allFinite())
      throw InputError("", "input point " + std::to_string(i) + " has a non-finite normal");
  }
}

}  // namespace

std::vector<Vec3f> vertex_normals(const TriangleMesh& mesh) {
  std::vector<Vec3f> normals(mesh.positions.size(), Vec3f::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vec3f& a = mesh.positions[t[0]];
    Vec3f n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);  // |n| = 2 area
    for (int k = 0; k < 3; ++k) normals[t[k]] += n;
  }
  for (Vec3f& n : normals) {
    float l = n.norm();
    n = l > 0.f ? Vec3f(n / l) : Vec3f::Zero();
  }
  return normals;
}

Reconstruction reconstruct(const OrientedPoints& points, const ReconstructOptions& options) {
  check_points(points);
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  Reconstruction result;
  ReconstructStats& stats = result.stats;
  stats.points = points.size();
  const CubeGrid grid = make_cube_grid(bounds(points.positions), options.resolution);
  const int R = grid.resolution;
  const float h = float(grid.cube_size);

  PointIndex index(points);

  // Seed cubes: those holding points, grown by the margin.
  std::vector<std::uint64_t> seeds(points.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t i = 0; i < points.size(); ++i) {
    Vec3d g = (points.positions[i].cast<double>() - grid.origin) / grid.cube_size;
    int c[3];
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor(g[a])), 0, R - 1);
    seeds[i] = pack_key(c[0], c[1], c[2]);
  }
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  if (options.margin > 0) {
    const int m = options.margin;
    std::vector<std::uint64_t> grown;
    grown.reserve(seeds.size() * 4);
    for (std::uint64_t key : seeds) {
      int x, y, z;
      unpack_key(key, &x, &y, &z);
      for (int dz = -m; dz <= m; ++dz)
        for (int dy = -m; dy <= m; ++dy)
          for (int dx = -m; dx <= m; ++dx) {
            int nx = x + dx, ny = y + dy, nz = z + dz;
            if (nx < 0 || ny < 0 || nz < 0 || nx >= R || ny >= R || nz >= R) continue;
            grown.push_back(pack_key(nx, ny, nz));
          }
    }
    std::sort(grown.begin(), grown.end());
    grown.erase(std::unique(grown.begin(), grown.end()), grown.end());
    seeds.swap(grown);
  }

  SparseGrid sg;
  sg.cube_index.reserve(seeds.size() * 5 / 4);
  sg.corner_index.reserve(seeds.size() * 2);
  for (std::uint64_t key : seeds) sg.add_cube(key);

  Progress progress("signed distances", seeds.size() * 2);
  std::size_t round_begin = 0;
  std::vector<Vec3f> queries;
  std::vector<float> new_distances;
  std::vector<std::int32_t> new_nearest;
  const bool have_spacing = points.spacing.size() == points.size();
  std::vector<std::uint8_t> accepted(sg.cube_keys.size(), 1);
  while (round_begin < sg.cube_keys.size()) {
    const std::size_t round_end = sg.cube_keys.size();
    accepted.resize(round_end, 1);
    if (round_begin > 0) {
      // Cubes reached by following: keep those whose centre is near a point.
      std::vector<Vec3f> centres(round_end - round_begin);
      for (std::size_t c = round_begin; c < round_end; ++c) {
        int x, y, z;
        unpack_key(sg.cube_keys[c], &x, &y, &z);
        centres[c - round_begin] = grid.corner_position(x, y, z) + Vec3f::Constant(0.5f * h);
      }
      std::vector<std::int32_t> nn(centres.size());
      std::vector<float> nd2(centres.size());
      index.knn(centres.data(), centres.size(), 1, nn.data(), nd2.data(), threads);
      for (std::size_t i = 0; i < centres.size(); ++i) {
        const float scale = std::max(h, have_spacing ? points.spacing[nn[i]] : 0.f);
        const float limit = options.reach * scale;
        accepted[round_begin + i] = nd2[i] <= limit * limit;
      }
    }
    // Corners of this round's cubes that no earlier cube shared.
    const std::size_t first_new_corner = sg.corner_keys.size();
    sg.cube_corners.resize(round_end);
    for (std::size_t c = round_begin; c < round_end; ++c) {
      if (!accepted[c]) continue;
      for (int k = 0; k < 8; ++k) {
        std::uint64_t ck = corner_key_of(sg.cube_keys[c], k);
        std::int32_t id = sg.corner_index.insert(ck, std::int32_t(sg.corner_keys.size()));
        if (id == std::int32_t(sg.corner_keys.size())) sg.corner_keys.push_back(ck);
        sg.cube_corners[c][k] = id;
      }
    }
    const std::size_t new_corners = sg.corner_keys.size() - first_new_corner;
    queries.resize(new_corners);
    for (std::size_t i = 0; i < new_corners; ++i) {
      int x, y, z;
      unpack_key(sg.corner_keys[first_new_corner + i], &x, &y, &z);
      queries[i] = grid.corner_position(x, y, z);
    }
    // In chunks, so that progress moves while FLANN works.
    const std::size_t chunk = 1 << 16;
    sg.corner_distances.resize(sg.corner_keys.size());
    sg.corner_nearest.resize(sg.corner_keys.size());
    for (std::size_t b = 0; b < new_corners; b += chunk) {
      std::size_t e = std::min(new_corners, b + chunk);
      std::vector<Vec3f> part(queries.begin() + b, queries.begin() + e);
      signed_distances(points, index, part, h, options.distance, threads, &new_distances,
                       &new_nearest);
      std::copy(new_distances.begin(), new_distances.end(),
                sg.corner_distances.begin() + first_new_corner + b);
      std::copy(new_nearest.begin(), new_nearest.end(),
                sg.corner_nearest.begin() + first_new_corner + b);
      progress.advance(e - b);
    }
    // Follow the surface: a face with a sign change on defined corners leads into
    // the neighbouring cube, which must be evaluated too or the mesh would end there.
    for (std::size_t c = round_begin; c < round_end; ++c) {
      if (!accepted[c]) continue;
      int x, y, z;
      unpack_key(sg.cube_keys[c], &x, &y, &z);
      const int xyz[3] = {x, y, z};
      for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
          int inside = 0, defined = 0;
          for (int k = 0; k < 8; ++k) {
            if (((k >> axis) & 1) != side) continue;
            float d = sg.corner_distances[sg.cube_corners[c][k]];
            if (std::isnan(d)) break;
            ++defined;
            inside += d < 0.f;
          }
          if (defined != 4 || inside == 0 || inside == 4) continue;
          int n = xyz[axis] + (side ? 1 : -1);
          if (n < 0 || n >= R) continue;
          std::uint64_t nk = side ? sg.cube_keys[c] + kAxisStep[axis] : sg.cube_keys[c] - kAxisStep[axis];
          sg.add_cube(nk);
        }
      }
    }
    round_begin = round_end;
    if (sg.cube_keys.size() > round_end) ++stats.following_rounds;
  }
  progress.finish();
  stats.cubes_touched = std::size_t(std::count(accepted.begin(), accepted.end(), 1));
  stats.corners_evaluated = sg.corner_keys.size();

  // Emitting cubes: all corners defined and a sign change.
  const auto& table = cube_cases();
  CubeNodes& leaves = result.leaves;
  leaves.grid = grid;
  for (std::size_t c = 0; c < sg.cube_keys.size(); ++c) {
    if (!accepted[c]) continue;
    std::uint8_t mask = 0;
    bool defined = true;
    for (int k = 0; k < 8; ++k) {
      float d = sg.corner_distances[sg.cube_corners[c][k]];
      if (std::isnan(d)) {
        defined = false;
        break;
      }
      mask |= std::uint8_t(d < 0.f) << k;
    }
    if (!defined || mask == 0 || mask == 255) continue;
    leaves.cube_keys.push_back(sg.cube_keys[c]);
    leaves.cases.push_back(mask);
    leaves.corners.push_back(sg.cube_corners[c]);
  }
  stats.cubes_emitting = leaves.size();

  // Shared vertices: one per crossed grid edge, keyed by its lower corner and axis.
  TriangleMesh& mesh = result.mesh;
  FlatHashMap edge_index(leaves.size() * 2);
  leaves.edge_vertices.resize(leaves.size());
  leaves.edge_ratios.resize(leaves.size());
  for (std::size_t c = 0; c < leaves.size(); ++c) {
    const CubeCase& cc = table[leaves.cases[c]];
    auto& ev = leaves.edge_vertices[c];
    auto& er = leaves.edge_ratios[c];
    for (int e = 0; e < 12; ++e) {
      ev[e] = -1;
      er[e] = 0.f;
      if (!(cc.edge_mask >> e & 1)) continue;
      const int a = edge_corner(e, 0), b = edge_corner(e, 1);
      const float da = sg.corner_distances[leaves.corners[c][a]];
      const float db = sg.corner_distances[leaves.corners[c][b]];
      // Ratio of |distances| (seed §4.2), kept off the corners so no triangle collapses.
      float t = std::fabs(da) / (std::fabs(da) + std::fabs(db));
      t = std::clamp(t, 1e-4f, 1.f - 1e-4f);
      er[e] = t;
      const std::uint64_t key = (corner_key_of(leaves.cube_keys[c], a) << 2) | std::uint64_t(e / 4);
      const std::int32_t id = edge_index.insert(key, std::int32_t(mesh.positions.size()));
      if (id == std::int32_t(mesh.positions.size())) {
        int x, y, z;
        unpack_key(corner_key_of(leaves.cube_keys[c], a), &x, &y, &z);
        Vec3f pa = grid.corner_position(x, y, z);
        Vec3f p = pa;
        p[e / 4] += t * h;
        mesh.positions.push_back(p);
      }
      ev[e] = id;
    }
    for (int t = 0; t < cc.triangle_count; ++t)
      mesh.triangles.push_back({ev[cc.triangles[t][0]], ev[cc.triangles[t][1]], ev[cc.triangles[t][2]]});
  }

  // Only the corners of emitting cubes are kept with the leaves.
  std::vector<std::int32_t> remap(sg.corner_keys.size(), -1);
  for (auto& corners : leaves.corners) {
    for (std::int32_t& id : corners) {
      if (remap[id] < 0) {
        remap[id] = std::int32_t(leaves.corner_keys.size());
        leaves.corner_keys.push_back(sg.corner_keys[id]);
        leaves.corner_distances.push_back(sg.corner_distances[id]);
        if (points.has_colors()) leaves.corner_colors.push_back(points.colors[sg.corner_nearest[id]]);
      }
      id = remap[id];
    }
  }

  mesh.normals = vertex_normals(mesh);
  if (points.has_colors()) {
    // Vertex colour: Gaussian-weighted mean of the nearest points' colours.
    const int k = std::min<int>(8, int(points.size()));
    std::vector<std::int32_t> idx(mesh.positions.size() * k);
    std::vector<float> d2(mesh.positions.size() * k);
    index.knn(mesh.positions.data(), mesh.positions.size(), k, idx.data(), d2.data(), threads);
    mesh.colors.resize(mesh.positions.size());
    const float inv = 1.f / (h * h);
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      float sum[3] = {0, 0, 0}, wsum = 0;
      for (int j = 0; j < k; ++j) {
        std::int32_t p = idx[v * k + j];
        if (p < 0) break;
        float w = std::exp(-(d2[v * k + j] - d2[v * k]) * inv);
        for (int ch = 0; ch < 3; ++ch) sum[ch] += w * points.colors[p][ch];
        wsum += w;
      }
      for (int ch = 0; ch < 3; ++ch)
        mesh.colors[v][ch] = std::uint8_t(std::clamp(sum[ch] / wsum + 0.5f, 0.f, 255.f));
    }
  }
  return result;
}

}  // namespace scan2lod
