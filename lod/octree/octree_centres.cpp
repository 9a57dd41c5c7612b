// Phases 7 and 11 of build_mc_octree: attributes of the vertices the octree
// adds, and the centre vertices of the transition fans (lod/octree/octree_build.h).
#include <scan2lod/lod/octree/octree_build.h>
#include <scan2lod/lod/octree/transition.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace scan2lod {
namespace octree_build {

// Phase 7.
void added_vertex_attributes(std::size_t first_new_vertex, McOctree* tree) {
  const std::size_t total = tree->vertices.positions.size();
  if (total > first_new_vertex) {
    tree->vertices.normals.resize(total, Vec3f::Zero());
    std::vector<Vec3f> colour_sum(total, Vec3f::Zero());
    std::vector<float> colour_count(total, 0.f);
    const bool colours = !tree->vertices.colors.empty();
    if (colours) tree->vertices.colors.resize(total, Rgb{0, 0, 0});
    for (const Triangle& t : tree->triangles) {
      const Vec3f nrm = (tree->vertices.positions[t[1]] - tree->vertices.positions[t[0]]).cross(tree->vertices.positions[t[2]] - tree->vertices.positions[t[0]]);
      for (int k = 0; k < 3; ++k) {
        if (std::size_t(t[k]) < first_new_vertex) continue;
        tree->vertices.normals[t[k]] += nrm;
        for (int j = 1; j < 3 && colours; ++j) {
          const std::int32_t other = t[(k + j) % 3];
          if (std::size_t(other) >= first_new_vertex) continue;
          colour_sum[t[k]] += Vec3f(tree->vertices.colors[other][0], tree->vertices.colors[other][1], tree->vertices.colors[other][2]);
          colour_count[t[k]] += 1.f;
        }
      }
    }
    for (std::size_t v = first_new_vertex; v < total; ++v) {
      tree->vertices.normals[v] = tree->vertices.normals[v].norm() > 0.f ? Vec3f(tree->vertices.normals[v].normalized()) : Vec3f::UnitZ();
      if (colours && colour_count[v] > 0.f) {
        const Vec3f c = colour_sum[v] / colour_count[v];
        tree->vertices.colors[v] = Rgb{std::uint8_t(c[0] + 0.5f), std::uint8_t(c[1] + 0.5f), std::uint8_t(c[2] + 0.5f)};
      }
    }
  }
}

namespace {

// The mean of a node's own crossings (of its boundary's where it has none),
// as a new vertex: -1 where nothing crosses its boundary (it never needs a fan).
void add_centre_vertices(McOctree* tree) {
  const std::int32_t internal = std::int32_t(tree->transitions.boundary_inside.size());
  tree->transitions.centre_vertices.assign(std::size_t(internal), -1);
  for (std::int32_t node = 0; node < internal; ++node) {
    Vec3f p = Vec3f::Zero(), nrm = Vec3f::Zero(), colour = Vec3f::Zero();
    int count = 0;
    auto add = [&](std::int32_t v) {
      if (v < 0) return;
      p += tree->vertices.positions[v];
      nrm += tree->vertices.normals[v];
      if (!tree->vertices.colors.empty()) colour += Vec3f(tree->vertices.colors[v][0], tree->vertices.colors[v][1], tree->vertices.colors[v][2]);
      ++count;
    };
    for (std::int32_t v : tree->nodes.edge_vertices[node]) add(v);
    if (count == 0)
      for (std::int32_t v : tree->transitions.sub_edge_vertices[node]) add(v);
    if (count == 0) continue;  // nothing crosses its boundary: it never needs a fan
    tree->transitions.centre_vertices[node] = std::int32_t(tree->vertices.positions.size());
    tree->vertices.positions.push_back(p / float(count));
    tree->vertices.normals.push_back(nrm.norm() > 0.f ? Vec3f(nrm.normalized()) : Vec3f::UnitZ());
    if (!tree->vertices.colors.empty()) {
      const Vec3f c = colour / float(count);
      tree->vertices.colors.push_back(Rgb{std::uint8_t(c[0] + 0.5f), std::uint8_t(c[1] + 0.5f), std::uint8_t(c[2] + 0.5f)});
    }
  }
}

// Moves each centre vertex to where the leaf triangles' planes under its node
// meet best (the quadric of Garland and Heckbert, *Surface Simplification Using Quadric
// Error Metrics* (1997), with the
// directions the planes do not pin down, eigenvalues under a tenth of the
// largest, left where they were): on a bend the fan's apex then sits off the
// surface, as far as its flat triangles need, instead of on it. At most half
// the node's size from the mean of the node's crossings. This made projecting
// the centre onto the field's zero set first redundant (without it the bunny's
// levels at R = 256 moved by at most 0.3 % of their error from 5 % up, and
// two field queries per node went).
void fit_centres(const std::vector<LeafSums>& sums, McOctree* tree) {
  const Eigen::Vector3d origin = tree->grid.origin;
  for (std::size_t node = 0; node < tree->internal_nodes(); ++node) {
    const std::int32_t v = tree->transitions.centre_vertices[node];
    if (v < 0) continue;
    const Eigen::Vector3d x0 = tree->vertices.positions[v].cast<double>() - origin;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(sums[node].planes);
    const Eigen::Vector3d values = solver.eigenvalues();
    const Eigen::Vector3d residual = sums[node].offsets - sums[node].planes * x0;
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k)
      if (values[k] > 0.1 * values[2] && values[k] > 0.0)
        step += solver.eigenvectors().col(k) * (solver.eigenvectors().col(k).dot(residual) / values[k]);
    const double size = node_size(*tree, node), limit = 0.5 * size;
    if (step.norm() > limit) step *= limit / step.norm();
    // Where the planes meet at one of the node's own crossings (a corner of
    // the surface), the fan's two triangles there would have no area: the
    // step is halved until the centre keeps clear of every crossing.
    auto clear_of_crossings = [&](const Eigen::Vector3d& x) {
      const Vec3f p = (x + origin).cast<float>();
      auto clear = [&](std::int32_t c) { return c < 0 || (tree->vertices.positions[std::size_t(c)] - p).norm() > 1e-3 * size; };
      return std::all_of(tree->nodes.edge_vertices[node].begin(), tree->nodes.edge_vertices[node].end(), clear) &&
             std::all_of(tree->transitions.sub_edge_vertices[node].begin(), tree->transitions.sub_edge_vertices[node].end(), clear);
    };
    for (int tries = 0; tries < 4 && !clear_of_crossings(x0 + step); ++tries) step *= 0.5;
    tree->vertices.positions[v] = (x0 + step + origin).cast<float>();
  }
}


// A node's transition fans over the typical layouts of finer neighbours: each
// loop side (a -> b, in loop order) with its loop, and each loop's unit
// vector area and mean.
struct FanSides {
  struct Side {
    Eigen::Vector3d a, b;
    int loop;
  };
  std::vector<Side> sides;
  std::vector<Eigen::Vector3d> loop_normals, loop_means;
  std::vector<int> loop_sizes;
  std::vector<Triangle> fans;  // scratch

  // How many fan triangles turn against their loop with the centre at c.
  int flips(const Eigen::Vector3d& c) const {
    int count = 0;
    for (const Side& s : sides) count += (s.a - c).cross(s.b - c).dot(loop_normals[std::size_t(s.loop)]) < 0.0;
    return count;
  }
};

// The layouts a centre is tried on: a finer node across each face alone, then
// across all six.
std::vector<std::uint32_t> typical_layouts() {
  std::vector<std::uint32_t> configurations;
  std::uint32_t all_faces = 0;
  for (const int c : splitting_cells())
    if (const std::uint32_t splits = cell_splits()[std::size_t(c)]; splits >> 12) {
      configurations.push_back(splits);
      all_faces |= splits;
    }
  configurations.push_back(all_faces);
  return configurations;
}

void collect_fan_sides(const McOctree& tree, std::size_t node, const std::vector<std::uint32_t>& configurations,
                       FanSides* f) {
  const std::int32_t centre = tree.transitions.centre_vertices[node];
  const auto& positions = tree.vertices.positions;
  f->sides.clear();
  f->loop_normals.clear();
  f->loop_means.clear();
  f->loop_sizes.clear();
  for (const std::uint32_t splits : configurations) {
    f->fans.clear();
    triangulate_transition({tree.transitions.boundary_inside[node], tree.nodes.edge_vertices[node].data(),
                            tree.transitions.sub_edge_vertices[node].data(), centre, std::uint8_t(splits >> 12),
                            std::uint16_t(splits & 0xfff)},
                           &f->fans);
    // A fan's triangles are (centre, loop[k + 1], loop[k]), one after
    // another: a loop ends where a triangle does not start at the last
    // one's loop[k + 1].
    const Triangle* previous = nullptr;
    for (const Triangle& t : f->fans) {
      if (t[0] != centre) continue;
      if (!previous || t[2] != (*previous)[1]) {
        f->loop_normals.push_back(Eigen::Vector3d::Zero());
        f->loop_means.push_back(Eigen::Vector3d::Zero());
        f->loop_sizes.push_back(0);
      }
      previous = &t;
      const Eigen::Vector3d a = positions[t[1]].cast<double>(), b = positions[t[2]].cast<double>();
      f->loop_normals.back() += a.cross(b);  // the loop's vector area, whatever the centre
      f->loop_means.back() += a;
      ++f->loop_sizes.back();
      f->sides.push_back({a, b, int(f->loop_normals.size()) - 1});
    }
  }
  for (std::size_t l = 0; l < f->loop_normals.size(); ++l) {
    f->loop_normals[l].normalize();
    f->loop_means[l] /= f->loop_sizes[l];
  }
}

// The point nearest c where every fan triangle faces its loop's way, by
// cyclic projections onto those half-spaces (at most 100 rounds).
Eigen::Vector3d project_to_unfolded(const FanSides& f, Eigen::Vector3d c, double size) {
  for (int round = 0; round < 100; ++round) {
    bool moved = false;
    for (const FanSides::Side& s : f.sides) {
      // Side a -> b faces its loop's way from c when g . c + h > 0.
      const Eigen::Vector3d& n = f.loop_normals[std::size_t(s.loop)];
      const Eigen::Vector3d g = (s.a - s.b).cross(n);
      const double h = s.a.cross(s.b).dot(n), margin = 1e-3 * size * (s.a - s.b).norm(), value = g.dot(c) + h;
      if (value < margin && g.squaredNorm() > 0.0) c += (margin - value) / g.squaredNorm() * g, moved = true;
    }
    if (!moved) break;
  }
  return c;
}

// The mean of a node's own crossings (of its boundary's where it has none).
Eigen::Vector3d crossing_mean(const McOctree& tree, std::size_t node) {
  Eigen::Vector3d own = Eigen::Vector3d::Zero();
  int count = 0;
  for (std::int32_t v : tree.nodes.edge_vertices[node])
    if (v >= 0) own += tree.vertices.positions[v].cast<double>(), ++count;
  if (count == 0)
    for (std::int32_t v : tree.transitions.sub_edge_vertices[node])
      if (v >= 0) own += tree.vertices.positions[v].cast<double>(), ++count;
  own /= double(std::max(1, count));
  return own;
}

// Moves centres whose transition fans would fold. A fan triangle whose side
// on the loop runs against the loop (seen from the centre) faces the wrong
// way: at R = 64 such triangles made every fold of the bunny's levels with
// normals more than 150 degrees apart. The loops depend on which neighbours
// are finer, so each node is tried on representative configurations (each
// face fine alone, every face fine; an edge split alone changed no fold's
// count on the bunny at R = 64 or 256, and cost 12 more); a centre that
// flips fewer fan triangles there replaces the fitted one: the nearest point
// where every fan triangle faces its loop's way (cyclic projections onto those
// half-spaces), else points towards the mean of the node's crossings or a
// loop's mean. Extraction still only reads the centre's index. A candidate
// more than half the node's size from its crossings' mean is not taken, the
// fit's own bound: unbounded, the projections put fan apexes up to 20 leaf
// cubes off an open scan: bun000's levels at 1000 and 2000 triangles
// (R = 256) were 11-13 % farther from the full mesh than with the bound,
// for as many folded edges.
void unfold_centres(McOctree* tree) {
  const std::vector<std::uint32_t> configurations = typical_layouts();
  const std::int64_t internal = std::int64_t(tree->internal_nodes());
  // Each node moves only its own centre, which no other node's loops hold.
#pragma omp parallel
  {
    FanSides f;
#pragma omp for schedule(dynamic, 256)
    for (std::int64_t node_index = 0; node_index < internal; ++node_index) {
      const std::size_t node = std::size_t(node_index);
      const std::int32_t centre = tree->transitions.centre_vertices[node];
      if (centre < 0) continue;
      collect_fan_sides(*tree, node, configurations, &f);
      if (f.sides.empty()) continue;
      const Eigen::Vector3d fitted = tree->vertices.positions[centre].cast<double>();
      int best = f.flips(fitted);
      if (best == 0) continue;
      std::vector<Eigen::Vector3d> candidates = {project_to_unfolded(f, fitted, node_size(*tree, node))};
      const Eigen::Vector3d own = crossing_mean(*tree, node);
      for (double t : {0.25, 0.5, 0.75, 1.0}) candidates.push_back(fitted + t * (own - fitted));
      candidates.insert(candidates.end(), f.loop_means.begin(), f.loop_means.end());
      const double reach = 0.5 * node_size(*tree, node);
      for (const Eigen::Vector3d& candidate : candidates) {
        if ((candidate - own).norm() > reach) continue;
        const int flips = f.flips(candidate);
        if (flips < best) best = flips, tree->vertices.positions[centre] = candidate.cast<float>();
      }
    }
  }
}

}  // namespace

void centre_vertices(const std::vector<LeafSums>& sums, McOctree* tree) {
  add_centre_vertices(tree);
  fit_centres(sums, tree);
  unfold_centres(tree);
}

}  // namespace octree_build
}  // namespace scan2lod
