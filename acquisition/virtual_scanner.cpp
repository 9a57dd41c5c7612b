#include <scan2lod/acquisition/virtual_scanner.h>

#include <scan2lod/acquisition/lattice_normals.h>
#include <scan2lod/acquisition/range_grid_ply.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <system_error>

namespace scan2lod {
namespace {

// Extra room around the bounding sphere's disc, so silhouettes are not clipped.
constexpr float kMargin = 1.02f;

// n directions spread evenly over the unit sphere (golden-spiral points):
// equal-area bands in z, longitudes advancing by the golden angle.
std::vector<Vec3f> fibonacci_directions(int n) {
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  std::vector<Vec3f> dirs(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden_angle * i;
    dirs[std::size_t(i)] = Vec3f(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
  }
  return dirs;
}

// Scan frame for a scanner on the +z side looking along -z, with z = `toward`
// (from the object to the scanner). y is the mesh's +y projected onto the
// image plane where possible, so views of a y-up model come out upright.
Eigen::Matrix3f scan_rotation(const Vec3f& toward) {
  const Vec3f z = toward.normalized();
  const Vec3f up = std::abs(z.y()) < 0.99f ? Vec3f::UnitY() : Vec3f::UnitZ();
  const Vec3f x = up.cross(z).normalized();
  const Vec3f y = z.cross(x);
  Eigen::Matrix3f r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

}  // namespace

std::vector<VirtualScan> virtual_scan(const TriangleMesh& mesh, const VirtualScanOptions& options) {
  if (options.views < 1 || options.width < 1 || options.height < 1)
    throw std::invalid_argument("virtual_scan: views, width and height must be >= 1");

  // Only triangles with area can be hit; the bounding sphere is theirs.
  const Aabb all = bounds(mesh.positions);
  const double tiny = 1e-12 * double(all.diagonal()) * double(all.diagonal());
  std::vector<std::uint32_t> solid;  // indices into mesh.triangles
  solid.reserve(mesh.triangles.size());
  Aabb used;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    const Vec3f& a = mesh.positions[tri[0]];
    const Vec3f& b = mesh.positions[tri[1]];
    const Vec3f& c = mesh.positions[tri[2]];
    const double area2 = (b - a).cast<double>().cross((c - a).cast<double>()).norm();
    if (!(area2 > tiny) || !std::isfinite(area2)) continue;
    solid.push_back(std::uint32_t(t));
    for (int k = 0; k < 3; ++k) used.extend(mesh.positions[tri[k]]);
  }
  if (solid.empty()) throw InputError("", "the mesh has no triangle with area to scan");
  const Vec3f center = (used.min + used.max) / 2;
  float radius = 0;
  for (std::uint32_t t : solid)
    for (int k = 0; k < 3; ++k)
      radius = std::max(radius, (mesh.positions[mesh.triangles[t][k]] - center).norm());

  const int W = options.width, H = options.height;
  const std::size_t samples = std::size_t(W) * std::size_t(H);
  // Square pixels; the shorter side spans the sphere's diameter plus margin.
  const double pixel = 2.0 * radius * kMargin / std::min(W, H);
  const bool colored = mesh.colors.size() == mesh.positions.size();
  const std::vector<Vec3f> directions = fibonacci_directions(options.views);

  std::vector<VirtualScan> scans(directions.size());
  Progress progress("virtual scans", directions.size());
#pragma omp parallel for schedule(dynamic)
  for (std::size_t view = 0; view < directions.size(); ++view) {
    VirtualScan& scan = scans[view];
    scan.pose.rotation = scan_rotation(directions[view]);
    scan.pose.translation = center;
    const Eigen::Matrix3d to_scan = scan.pose.rotation.transpose().cast<double>();

    // Parallel rays through pixel centres: the first hit along -z is the
    // largest z among the triangles covering the centre, i.e. a z-buffer.
    // Lattice coordinates: column u = x/pixel + W/2 - 1/2, row v = H/2 - 1/2 - y/pixel.
    std::vector<double> depth(samples, -std::numeric_limits<double>::infinity());
    std::vector<std::int32_t> hit(samples, -1);         // index into solid
    std::vector<Eigen::Vector3f> weights(samples);      // barycentrics of the hit
    for (std::size_t s = 0; s < solid.size(); ++s) {
      const Triangle& tri = mesh.triangles[solid[s]];
      Eigen::Vector3d q[3];
      double u[3], v[3];
      for (int k = 0; k < 3; ++k) {
        q[k] = to_scan * (mesh.positions[tri[k]] - center).cast<double>();
        u[k] = q[k].x() / pixel + 0.5 * W - 0.5;
        v[k] = 0.5 * H - 0.5 - q[k].y() / pixel;
      }
      const double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
      if (std::abs(area) < 1e-12) continue;  // seen edge-on: rays graze it
      const int c0 = std::max(0, int(std::ceil(std::min({u[0], u[1], u[2]}))));
      const int c1 = std::min(W - 1, int(std::floor(std::max({u[0], u[1], u[2]}))));
      const int r0 = std::max(0, int(std::ceil(std::min({v[0], v[1], v[2]}))));
      const int r1 = std::min(H - 1, int(std::floor(std::max({v[0], v[1], v[2]}))));
      for (int r = r0; r <= r1; ++r) {
        for (int c = c0; c <= c1; ++c) {
          // Edge functions, normalised; both windings count (a scanner sees
          // the inside of an open surface too). The tolerance keeps centres
          // on a shared edge from falling through both neighbours.
          const double w0 = ((u[2] - u[1]) * (r - v[1]) - (c - u[1]) * (v[2] - v[1])) / area;
          const double w1 = ((u[0] - u[2]) * (r - v[2]) - (c - u[2]) * (v[0] - v[2])) / area;
          const double w2 = 1.0 - w0 - w1;
          constexpr double eps = -1e-9;
          if (w0 < eps || w1 < eps || w2 < eps) continue;
          const double z = w0 * q[0].z() + w1 * q[1].z() + w2 * q[2].z();
          const std::size_t i = std::size_t(r) * std::size_t(W) + std::size_t(c);
          if (z <= depth[i]) continue;
          depth[i] = z;
          hit[i] = std::int32_t(s);
          weights[i] = Eigen::Vector3f(float(w0), float(w1), float(w2));
        }
      }
    }

    RangeImage& image = scan.image;
    image.cols = W;
    image.rows = H;
    image.points.assign(samples, Vec3f::Constant(std::numeric_limits<float>::quiet_NaN()));
    image.confidence.assign(samples, 0.f);
    if (colored) image.colors.assign(samples, Rgb{0, 0, 0});
    char name[32];
    std::snprintf(name, sizeof name, "scan_%03zu", view);
    image.source = name;
    for (std::size_t i = 0; i < samples; ++i) {
      if (hit[i] < 0) continue;
      const int r = int(i / std::size_t(W)), c = int(i % std::size_t(W));
      image.points[i] = Vec3f(float((c + 0.5 - 0.5 * W) * pixel),
                              float((0.5 * H - 0.5 - r) * pixel), float(depth[i]));
      const Triangle& tri = mesh.triangles[solid[std::size_t(hit[i])]];
      const Vec3f n = (mesh.positions[tri[1]] - mesh.positions[tri[0]])
                          .cross(mesh.positions[tri[2]] - mesh.positions[tri[0]]);
      // |cos| between the ray (the scan frame's z) and the surface normal.
      image.confidence[i] = std::abs(n.dot(scan.pose.rotation.col(2))) / n.norm();
      if (colored) {
        for (int ch = 0; ch < 3; ++ch) {
          float value = 0;
          for (int k = 0; k < 3; ++k) value += weights[i][k] * float(mesh.colors[tri[k]][ch]);
          image.colors[i][ch] = std::uint8_t(std::lround(std::clamp(value, 0.f, 255.f)));
        }
      }
    }
    progress.advance();
  }
  progress.finish();
  return scans;
}

OrientedPoints virtual_scan_points(const TriangleMesh& mesh, const VirtualScanOptions& options) {
  OrientedPoints points;
  for (const VirtualScan& scan : virtual_scan(mesh, options)) points.append(range_image_to_points(scan.image, scan.pose));
  return points;
}

}  // namespace scan2lod
