#include <scan2lod/acquisition/lattice_normals.h>

#include <cmath>
#include <limits>

namespace scan2lod {

OrientedPoints range_image_to_points(const RangeImage& image, const ScanPose& pose,
                                     const LatticeNormalOptions& options) {
  const int W = image.cols, H = image.rows;
  auto valid = [&](int r, int c) {
    return r >= 0 && r < H && c >= 0 && c < W && std::isfinite(image.points[std::size_t(r) * W + c].x());
  };
  OrientedPoints out;
  const bool colors = image.colors.size() == image.points.size();
  const bool confidence = image.confidence.size() == image.points.size();
  // Neighbours in angular order, so consecutive pairs span the 4 lattice triangles.
  const int dr[4] = {0, -1, 0, 1};
  const int dc[4] = {1, 0, -1, 0};
  for (int r = 0; r < H; ++r) {
    for (int c = 0; c < W; ++c) {
      if (!valid(r, c)) continue;
      const Vec3f& p = image.points[std::size_t(r) * W + c];
      // Zeroed: GCC cannot see that only the ok[] ones are read.
      Vec3f d[4] = {Vec3f::Zero(), Vec3f::Zero(), Vec3f::Zero(), Vec3f::Zero()};
      float len[4] = {0, 0, 0, 0};
      bool ok[4];
      float shortest = std::numeric_limits<float>::max();
      for (int k = 0; k < 4; ++k) {
        ok[k] = valid(r + dr[k], c + dc[k]);
        if (!ok[k]) continue;
        d[k] = image.points[std::size_t(r + dr[k]) * W + (c + dc[k])] - p;
        len[k] = d[k].norm();
        if (len[k] <= 0.f) ok[k] = false;
        else shortest = std::min(shortest, len[k]);
      }
      const float limit = options.max_edge_ratio * shortest;
      Vec3f sum = Vec3f::Zero();
      float edge_sum = 0.f;
      int edges = 0, triangles = 0;
      for (int k = 0; k < 4; ++k) {
        int j = (k + 1) & 3;
        if (!ok[k] || !ok[j] || len[k] > limit || len[j] > limit) continue;
        // The far edge of the triangle must be short too, or it bridges a gap.
        if ((d[j] - d[k]).norm() > limit) continue;
        Vec3f n = d[k].cross(d[j]);
        float nl = n.norm();
        if (nl <= 0.f) continue;
        sum += n / nl;
        ++triangles;
      }
      if (triangles == 0) continue;
      for (int k = 0; k < 4; ++k)
        if (ok[k] && len[k] <= limit) edge_sum += len[k], ++edges;
      float sl = sum.norm();
      if (sl <= 1e-6f) continue;
      Vec3f n = sum / sl;
      const Vec3f to_scanner = image.viewpoint ? Vec3f(*image.viewpoint - p) : Vec3f::UnitZ();
      if (n.dot(to_scanner) < 0.f) n = -n;
      out.positions.push_back(pose.rotation * p + pose.translation);
      out.normals.push_back(pose.rotation * n);
      out.spacing.push_back(edge_sum / float(edges));
      if (colors) out.colors.push_back(image.colors[std::size_t(r) * W + c]);
      // Without a scanner confidence, the cosine of the view angle stands in:
      // grazing samples are the noisiest (Curless & Levoy 1996).
      out.confidence.push_back(confidence ? image.confidence[std::size_t(r) * W + c]
                                          : std::max(0.f, n.dot(to_scanner.normalized())));
    }
  }
  return out;
}

}  // namespace scan2lod
