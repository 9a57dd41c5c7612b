#include <scan2lod/delivery/tile_gaps.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <limits>
#include <memory>
#include <unordered_map>

namespace scan2lod {
namespace {

// Ericson, *Real-Time Collision Detection* (2005), §5.1.5: the point of
// triangle abc nearest p.
Vec3f closest_on_triangle(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denom = 1 / (va + vb + vc);
  if (!std::isfinite(denom)) return a;  // a degenerate triangle: its corner
  return a + ab * (vb * denom) + ac * (vc * denom);
}

bool contains(const Aabb& box, const Vec3f& p) {
  return (box.min.array() <= p.array()).all() && (p.array() <= box.max.array()).all();
}

// A tile's triangles bucketed on a grid over its content box, for nearest-
// triangle queries.
class TriangleGrid {
 public:
  TriangleGrid(const TileContent& content, const Tile& tile) : content_(&content), tile_(&tile) {
    const VertexArray& v = content.vertices;
    const Vec3f extent = tile.content_box.extent();
    const float cells = std::max(1.f, std::cbrt(float(content.triangles.size()) / 4.f));
    size_ = std::max(extent.maxCoeff() / cells, 1e-20f);
    for (std::size_t t = 0; t < content.triangles.size(); ++t) {
      Aabb box;
      for (std::int32_t i : content.triangles[t]) box.extend(v.positions[std::size_t(i)]);
      const auto lo = cell_of(box.min), hi = cell_of(box.max);
      for (long x = lo[0]; x <= hi[0]; ++x)
        for (long y = lo[1]; y <= hi[1]; ++y)
          for (long z = lo[2]; z <= hi[2]; ++z) cells_[key(x, y, z)].push_back(std::int32_t(t));
    }
  }

  // The distance from p to the nearest triangle.
  double distance(const Vec3f& p) const {
    float best = std::numeric_limits<float>::infinity();
    const auto c = cell_of(p);
    const long reach = long(std::ceil(tile_->content_box.extent().maxCoeff() / size_)) + 2;
    for (long r = 0; r <= reach; ++r) {
      if (float(r - 1) * size_ > best) break;  // every cell of this ring is farther
      for (long x = c[0] - r; x <= c[0] + r; ++x)
        for (long y = c[1] - r; y <= c[1] + r; ++y)
          for (long z = c[2] - r; z <= c[2] + r; ++z) {
            if (std::max({std::labs(x - c[0]), std::labs(y - c[1]), std::labs(z - c[2])}) != r) continue;
            const auto it = cells_.find(key(x, y, z));
            if (it == cells_.end()) continue;
            for (std::int32_t t : it->second) {
              const Triangle& tri = content_->triangles[std::size_t(t)];
              const VertexArray& v = content_->vertices;
              const Vec3f q = closest_on_triangle(p, v.positions[std::size_t(tri[0])],
                                                  v.positions[std::size_t(tri[1])],
                                                  v.positions[std::size_t(tri[2])]);
              best = std::min(best, (q - p).norm());
            }
          }
    }
    return best;
  }

 private:
  std::array<long, 3> cell_of(const Vec3f& p) const {
    return {long(std::floor(p.x() / size_)), long(std::floor(p.y() / size_)), long(std::floor(p.z() / size_))};
  }
  static std::uint64_t key(long x, long y, long z) {
    return (std::uint64_t(x & 0x1FFFFF) << 42) | (std::uint64_t(y & 0x1FFFFF) << 21) | std::uint64_t(z & 0x1FFFFF);
  }
  const TileContent* content_;
  const Tile* tile_;
  float size_;
  std::unordered_map<std::uint64_t, std::vector<std::int32_t>> cells_;
};

// Points on the tile's seam: the ends and middles of the edges only one of
// its triangles uses, where the edge lies outside the tile's cell.
std::vector<Vec3f> seam_points(const TileContent& content, const Tile& tile) {
  const VertexArray& v = content.vertices;
  std::unordered_map<std::uint64_t, int> uses;
  for (const Triangle& t : content.triangles)
    for (int k = 0; k < 3; ++k) ++uses[edge_key(t[k], t[(k + 1) % 3])];
  std::vector<Vec3f> points;
  for (const auto& [key, n] : uses) {
    if (n != 1) continue;
    const Vec3f a = v.positions[std::size_t(key >> 32)], b = v.positions[std::size_t(key & 0xFFFFFFFFu)];
    if (contains(tile.cell, a) || contains(tile.cell, b)) continue;  // a scan's own border inside the cell
    points.push_back(a);
    points.push_back(b);
    points.push_back((a + b) * 0.5f);
  }
  return points;
}

bool ancestor_of(const TileTree& tree, int a, int b) {
  for (int t = tree.tiles[std::size_t(b)].parent; t >= 0; t = tree.tiles[std::size_t(t)].parent)
    if (t == a) return true;
  return false;
}

void add(TileGapStats* s, double gap, double error, double tolerance) {
  ++s->points;
  s->max_gap = std::max(s->max_gap, gap);
  if (error > 0) s->max_ratio = std::max(s->max_ratio, gap / error);
  if (gap > error + tolerance) ++s->over;
}

}  // namespace

TileGaps measure_tile_gaps(const TileTree& tree, const std::vector<TileContent>& contents, double tolerance,
                           int depth_differences) {
  TileGaps out;
  out.by_depth_difference.resize(std::size_t(std::max(1, depth_differences)));
  std::vector<std::unique_ptr<TriangleGrid>> grids(tree.tiles.size());
  for (std::size_t a = 0; a < tree.tiles.size(); ++a) {
    const Tile& ta = tree.tiles[a];
    if (!ta.has_content()) continue;
    for (const Vec3f& p : seam_points(contents[a], ta)) {
      // The tiles whose cells hold p, one per depth at most, found from the root.
      for (int b = 0; b >= 0;) {
        const Tile& tb = tree.tiles[std::size_t(b)];
        if (tb.has_content() && !ancestor_of(tree, b, int(a)) && !ancestor_of(tree, int(a), b) && b != int(a)) {
          std::unique_ptr<TriangleGrid>& grid = grids[std::size_t(b)];
          if (!grid) grid = std::make_unique<TriangleGrid>(contents[std::size_t(b)], tb);
          const double gap = grid->distance(p);
          const double error = std::max(ta.geometric_error, tb.geometric_error);
          const std::size_t d = std::min<std::size_t>(std::size_t(std::abs(ta.depth - tb.depth)),
                                                      out.by_depth_difference.size() - 1);
          add(&out.by_depth_difference[d], gap, error, tolerance);
          add(&out.all, gap, error, tolerance);
        }
        int next = -1;
        for (int c : tb.children)
          if (contains(tree.tiles[std::size_t(c)].cell, p)) {
            next = c;
            break;
          }
        b = next;
      }
    }
  }
  return out;
}

}  // namespace scan2lod
