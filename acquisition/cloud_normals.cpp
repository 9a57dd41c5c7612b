#include <scan2lod/acquisition/cloud_normals.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/spatial/point_index.h>

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <omp.h>

#include <algorithm>
#include <optional>
#include <array>
#include <queue>
#include <cmath>

namespace scan2lod {
namespace {

// The cloud's finite points with usable normals, normalised.
OrientedPoints given_normals(const PointCloud& cloud) {
  OrientedPoints points;
  const bool colored = cloud.colors.size() == cloud.size();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vec3f& n = cloud.normals[i];
    const float length = n.norm();
    if (!cloud.positions[i].allFinite() || !(length > 0.f) || !std::isfinite(length)) continue;
    points.positions.push_back(cloud.positions[i]);
    points.normals.push_back(n / length);
    if (colored) points.colors.push_back(cloud.colors[i]);
  }
  return points;
}

// Turns each piece's normals around when most of its six extreme points
// (lowest and highest along each axis) have normals pointing into it: on the
// hull the outside is known.
void face_outward(OrientedPoints* points, const std::vector<std::int32_t>& piece, std::int32_t pieces) {
  std::vector<std::array<std::int32_t, 6>> extreme(static_cast<std::size_t>(pieces));
  for (auto& e : extreme) e.fill(-1);
  for (std::size_t i = 0; i < points->size(); ++i) {
    auto& e = extreme[std::size_t(piece[i])];
    for (int axis = 0; axis < 3; ++axis) {
      const float x = points->positions[i][axis];
      if (e[2 * axis] < 0 || x < points->positions[std::size_t(e[2 * axis])][axis]) e[2 * axis] = std::int32_t(i);
      if (e[2 * axis + 1] < 0 || x > points->positions[std::size_t(e[2 * axis + 1])][axis])
        e[2 * axis + 1] = std::int32_t(i);
    }
  }
  std::vector<std::uint8_t> flip(static_cast<std::size_t>(pieces), 0);
  for (std::size_t p = 0; p < extreme.size(); ++p) {
    int votes = 0;
    for (int axis = 0; axis < 3; ++axis) {
      votes += points->normals[std::size_t(extreme[p][2 * axis + 1])][axis] > 0.f ? 1 : -1;
      votes += points->normals[std::size_t(extreme[p][2 * axis])][axis] < 0.f ? 1 : -1;
    }
    flip[p] = votes < 0;
  }
  for (std::size_t i = 0; i < points->size(); ++i)
    if (flip[std::size_t(piece[i])]) points->normals[i] = -points->normals[i];
}

// Turns each piece's normals around when, summed, they point away from a
// sensor in `direction`: every surface a far sensor sampled faced it, but a
// single normal near the horizontal can go either way, so the piece decides.
void face_direction(OrientedPoints* points, const std::vector<std::int32_t>& piece, std::int32_t pieces,
                    const Vec3f& direction) {
  std::vector<double> toward(static_cast<std::size_t>(pieces), 0.0);
  for (std::size_t i = 0; i < points->size(); ++i) toward[std::size_t(piece[i])] += points->normals[i].dot(direction);
  for (std::size_t i = 0; i < points->size(); ++i)
    if (toward[std::size_t(piece[i])] < 0.0) points->normals[i] = -points->normals[i];
}

// Orients normals consistently by propagating along a minimum spanning tree
// of the k-nearest-neighbour graph, edges weighted 1 - |n_i . n_j| so that the
// orientation crosses where neighbouring planes agree (Hoppe et al. 1992).
// Each connected piece of the graph is then turned outward on its own, or
// toward a far sensor's `direction` when there is one (an airborne scan's
// ground has no outside for the hull to tell).
void orient_consistently(OrientedPoints* points, int k, int threads, const std::optional<Vec3f>& direction) {
  const std::size_t n = points->size();
  k = std::min<int>(k + 1, int(n));
  std::vector<std::int32_t> nn(n * std::size_t(k));
  std::vector<float> d2(n * std::size_t(k));
  const PointIndex index(*points);
  index.knn(points->positions.data(), n, k, nn.data(), d2.data(), threads);
  // The graph is the kNN relation made symmetric: both endpoints list an edge.
  std::vector<std::int32_t> degree(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    for (int j = 1; j < k; ++j)
      if (nn[i * k + j] >= 0) ++degree[i + 1], ++degree[std::size_t(nn[i * k + j]) + 1];
  for (std::size_t i = 0; i < n; ++i) degree[i + 1] += degree[i];
  std::vector<std::int32_t> adjacency(static_cast<std::size_t>(degree[n]));
  std::vector<std::int32_t> fill(degree.begin(), degree.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    for (int j = 1; j < k; ++j) {
      const std::int32_t o = nn[i * k + j];
      if (o < 0) continue;
      adjacency[std::size_t(fill[i]++)] = o;
      adjacency[std::size_t(fill[std::size_t(o)]++)] = std::int32_t(i);
    }
  std::vector<Vec3f>& normals = points->normals;
  std::vector<std::uint8_t> done(n, 0);
  std::vector<std::int32_t> piece(n, -1);
  // Prim's algorithm with a lazy heap: (weight, point, the tree point it hangs from).
  struct Entry {
    float weight;
    std::int32_t point, from;
    bool operator>(const Entry& o) const { return weight > o.weight; }
  };
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  std::vector<float> best(n, 2.f);
  std::int32_t pieces = 0;
  for (std::size_t root = 0; root < n; ++root) {
    if (done[root]) continue;
    queue.push({0.f, std::int32_t(root), -1});
    while (!queue.empty()) {
      const Entry e = queue.top();
      queue.pop();
      const std::int32_t i = e.point;
      if (done[i]) continue;
      done[i] = 1;
      piece[i] = pieces;
      if (e.from >= 0 && normals[i].dot(normals[e.from]) < 0.f) normals[i] = -normals[i];
      for (std::int32_t a = degree[i]; a < degree[i + 1]; ++a) {
        const std::int32_t j = adjacency[std::size_t(a)];
        const float w = 1.f - std::fabs(normals[i].dot(normals[j]));
        if (done[j] || !(w < best[j])) continue;
        best[j] = w;
        queue.push({w, j, i});
      }
    }
    ++pieces;
  }
  if (direction) face_direction(points, piece, pieces, *direction);
  else face_outward(points, piece, pieces);
}

// Normals from the positions alone: Open3D's local plane fits, then turned
// toward the sensor when the file names one, else oriented consistently and
// turned outward, or toward a far sensor's direction (LAS: +Z).
OrientedPoints estimated_normals(const PointCloud& cloud, const CloudNormalOptions& options) {
  open3d::geometry::PointCloud o3d;
  std::vector<std::size_t> kept;
  o3d.points_.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (cloud.positions[i].allFinite()) {
      o3d.points_.push_back(cloud.positions[i].cast<double>());
      kept.push_back(i);
    }
  if (kept.size() < 3) return {};
  Progress progress("estimating normals", 3);
  o3d.EstimateNormals(open3d::geometry::KDTreeSearchParamKNN(options.neighbours));
  progress.advance();
  if (cloud.viewpoint) o3d.OrientNormalsTowardsCameraLocation(cloud.viewpoint->cast<double>());
  OrientedPoints points;
  const bool colored = cloud.colors.size() == cloud.size();
  for (std::size_t j = 0; j < kept.size(); ++j) {
    const Vec3f n = o3d.normals_[j].cast<float>();
    if (!n.allFinite() || !(n.norm() > 0.5f)) continue;
    points.positions.push_back(cloud.positions[kept[j]]);
    points.normals.push_back(n.normalized());
    if (colored) points.colors.push_back(cloud.colors[kept[j]]);
  }
  progress.advance();
  if (!cloud.viewpoint && points.size() > 1)
    orient_consistently(&points, options.orient_neighbours, options.threads, cloud.sensor_direction);
  progress.finish();
  return points;
}

// spacing = mean distance to the nearest few other points.
void estimate_spacing(OrientedPoints* points, const CloudNormalOptions& options) {
  const PointIndex index(*points);
  const int k = std::min<int>(options.spacing_neighbours + 1, int(points->size()));
  const std::size_t chunk = 1 << 16;
  std::vector<std::int32_t> idx(chunk * k);
  std::vector<float> d2(chunk * k);
  points->spacing.resize(points->size());
  for (std::size_t b = 0; b < points->size(); b += chunk) {
    const std::size_t n = std::min(chunk, points->size() - b);
    index.knn(&points->positions[b], n, k, idx.data(), d2.data(), options.threads);
    for (std::size_t i = 0; i < n; ++i) {
      float sum = 0.f;
      int count = 0;
      for (int j = 1; j < k; ++j)  // j = 0 is the point itself
        if (idx[i * k + j] >= 0) sum += std::sqrt(d2[i * k + j]), ++count;
      points->spacing[b + i] = count ? sum / float(count) : 0.f;
    }
  }
}

}  // namespace

OrientedPoints cloud_to_oriented_points(const PointCloud& cloud, const CloudNormalOptions& options) {
  OrientedPoints points = cloud.normals.size() == cloud.size() && cloud.size() > 0
                              ? given_normals(cloud)
                              : estimated_normals(cloud, options);
  if (points.size() < 3)
    throw InputError(cloud.source, "holds " + std::to_string(points.size()) +
                                       " usable points; a surface needs at least 3 with finite "
                                       "coordinates (and non-zero normals, where the file gives normals)");
  estimate_spacing(&points, options);
  return points;
}

}  // namespace scan2lod
