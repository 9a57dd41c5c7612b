#include <scan2lod/lod/lod_model.h>

#include <scan2lod/core/compact_mesh.h>
#include <scan2lod/core/error.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/octree/extract.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace scan2lod {

const char* structure_name(LodStructure s) { return s == LodStructure::kOctree ? "octree" : "clusters"; }

std::vector<std::string> structure_names() {
  return {structure_name(LodStructure::kClusters), structure_name(LodStructure::kOctree)};
}

LodStructure default_structure(const LodModel& model) {
  return model.clusters ? LodStructure::kClusters : LodStructure::kOctree;
}

LodStructure structure_named(const LodModel& model, const std::string& name, const std::string& source) {
  LodStructure s = default_structure(model);
  if (name == "clusters") s = LodStructure::kClusters;
  else if (name == "octree") s = LodStructure::kOctree;
  else if (!name.empty()) throw InputError("", "--structure must be clusters or octree, got '" + name + "'");
  require_structure(model, s, source);
  return s;
}

void require_structure(const LodModel& model, LodStructure s, const std::string& source) {
  if (!model.has(s))
    throw InputError(source, std::string("the model has no ") + structure_name(s) + " structure (it holds " +
                                 (model.octree && model.clusters ? "both"
                                  : model.octree                 ? "only the octree"
                                                                 : "only the cluster hierarchy") +
                                 "); rebuild it with scan2lod build --structure " + structure_name(s) + " or both");
}

LodModel model_from_octree(McOctree tree, LodArray lod) {
  LodModel model;
  model.vertices = std::move(tree.vertices);
  tree.vertices = {};
  model.octree = OctreeLod{std::move(tree), std::move(lod)};
  return model;
}

namespace {

// The vertices the hierarchy's collapses placed, after the model's: they were
// numbered from its count. The hierarchy's range grows to take them in.
void take_added_vertices(LodModel* model) {
  ClusterHierarchy& h = *model->clusters;
  VertexArray& v = model->vertices;
  if (!h.added_positions.empty()) {
    if (model->cluster_vertex_first + model->cluster_vertex_count != v.size())
      model->cluster_vertex_count = v.size() - model->cluster_vertex_first;
    v.positions.insert(v.positions.end(), h.added_positions.begin(), h.added_positions.end());
    if (!v.normals.empty()) v.normals.insert(v.normals.end(), h.added_normals.begin(), h.added_normals.end());
    if (!v.colors.empty()) v.colors.insert(v.colors.end(), h.added_colors.begin(), h.added_colors.end());
    model->cluster_vertex_count += h.added_positions.size();
  }
  h.added_positions = {};
  h.added_normals = {};
  h.added_colors = {};
}

}  // namespace

void add_cluster_hierarchy(LodModel* model, TriangleMesh&& mesh, bool shares_vertices, const ClusterOptions& options) {
  VertexArray& v = model->vertices;
  std::size_t first = 0;
  const std::size_t count = mesh.positions.size();
  if (shares_vertices) {
    model->clusters = build_cluster_hierarchy(v.positions, v.normals, v.colors, std::move(mesh.triangles), options);
    model->cluster_vertex_first = 0;
    model->cluster_vertex_count = count;
    take_added_vertices(model);
    return;
  }
  if (v.positions.empty()) {
    // The mesh's vertices become the model's, each array freed once copied
    // (the model's arrays have their own allocator).
    auto take = [](auto& to, auto& from) {
      to.assign(from.begin(), from.end());
      from = {};
    };
    take(v.positions, mesh.positions);
    take(v.normals, mesh.normals);
    take(v.colors, mesh.colors);
  } else {
    first = v.size();
    // An attribute present on one side only is filled on the other, so that
    // the arrays stay one per position.
    const bool normals = !v.normals.empty() || !mesh.normals.empty();
    const bool colors = !v.colors.empty() || !mesh.colors.empty();
    v.positions.insert(v.positions.end(), mesh.positions.begin(), mesh.positions.end());
    if (normals) {
      v.normals.resize(first, Vec3f::Zero());
      if (mesh.normals.empty()) v.normals.resize(v.size(), Vec3f::Zero());
      else v.normals.insert(v.normals.end(), mesh.normals.begin(), mesh.normals.end());
    }
    if (colors) {
      v.colors.resize(first, Rgb{200, 200, 200});
      if (mesh.colors.empty()) v.colors.resize(v.size(), Rgb{200, 200, 200});
      else v.colors.insert(v.colors.end(), mesh.colors.begin(), mesh.colors.end());
    }
  }
  if (first > 0)
    for (Triangle& t : mesh.triangles)
      for (std::int32_t& i : t) i += std::int32_t(first);
  model->clusters = build_cluster_hierarchy(v.positions, v.normals, v.colors, std::move(mesh.triangles), options);
  model->cluster_vertex_first = first;
  model->cluster_vertex_count = count;
  take_added_vertices(model);
}

void add_cluster_hierarchy(LodModel* model, const TriangleMesh& mesh, bool shares_vertices,
                           const ClusterOptions& options) {
  if (shares_vertices) {
    model->clusters = build_cluster_hierarchy(model->vertices.positions, model->vertices.normals,
                                              model->vertices.colors, mesh.triangles, options);
    model->cluster_vertex_first = 0;
    model->cluster_vertex_count = mesh.positions.size();
    take_added_vertices(model);
    return;
  }
  add_cluster_hierarchy(model, TriangleMesh(mesh), false, options);
}

static LevelRequest request_of(LevelRequest::Kind kind) {
  LevelRequest r;
  r.kind = kind;
  return r;
}
LevelRequest LevelRequest::at_percent(double p) {
  LevelRequest r = request_of(Kind::kPercent);
  r.percent = p;
  return r;
}
LevelRequest LevelRequest::at_triangles(std::int64_t t) {
  LevelRequest r = request_of(Kind::kTriangles);
  r.triangles = t;
  return r;
}
LevelRequest LevelRequest::at_most_triangles(std::int64_t t) {
  LevelRequest r = at_triangles(t);
  r.strict = true;
  return r;
}
LevelRequest LevelRequest::at_error(double e) {
  LevelRequest r = request_of(Kind::kError);
  r.error = e;
  return r;
}
LevelRequest LevelRequest::for_camera(const CameraView& c, double pixel_error) {
  LevelRequest r = request_of(Kind::kCamera);
  r.camera = c;
  r.pixel_error = pixel_error;
  return r;
}
LevelRequest LevelRequest::at_priority(std::size_t p) {
  LevelRequest r = request_of(Kind::kPriority);
  r.priority = p;
  return r;
}

LevelExtractor::LevelExtractor(const LodModel& model, LodStructure structure) : model_(&model), structure_(structure) {
  require_structure(model, structure, "");
  if (structure == LodStructure::kClusters) table_ = cluster_cut_table(*model.clusters);
}

std::int64_t LevelExtractor::full_triangles() const {
  return structure_ == LodStructure::kClusters ? model_->clusters->full_triangles
                                               : model_->octree->lod.accumulated.back();
}

std::int64_t LevelExtractor::coarsest_triangles() const {
  if (structure_ == LodStructure::kClusters) return table_.triangles.back();
  const LodArray& lod = model_->octree->lod;
  return lod.accumulated[priority_for_percent(lod, 0)];
}

std::pair<std::int64_t, std::int64_t> LevelExtractor::offered_around(std::int64_t triangles) const {
  std::int64_t under = -1, over = -1;
  auto see = [&](std::int64_t count) {
    if (count <= triangles) under = std::max(under, count);
    else if (over < 0 || count < over) over = count;
  };
  if (structure_ == LodStructure::kClusters) {
    for (const std::int64_t count : table_.triangles) see(count);
  } else {
    const LodArray& lod = model_->octree->lod;
    for (const std::size_t p : monotone_priorities(lod)) see(lod.accumulated[p]);
  }
  return {under, over};
}

int LevelExtractor::levels() const {
  return structure_ == LodStructure::kClusters ? model_->clusters->levels() : model_->octree->tree.depth + 1;
}

std::vector<std::uint8_t> LevelExtractor::triangle_levels() const {
  std::vector<std::uint8_t> out;
  out.reserve(cut_.triangles.size());
  if (structure_ == LodStructure::kClusters) {
    for (std::int32_t c : selected_) {
      const Cluster& cl = model_->clusters->clusters[std::size_t(c)];
      out.insert(out.end(), cl.triangle_count, cl.level);
    }
  } else {
    out.assign(cut_.triangles.size(), 0);
  }
  return out;
}

std::size_t LevelExtractor::octree_priority(const LevelRequest& request) const {
  const LodArray& lod = model_->octree->lod;
  using Kind = LevelRequest::Kind;
  switch (request.kind) {
    case Kind::kPercent: return priority_for_percent(lod, request.percent);
    case Kind::kTriangles:
      return request.strict ? priority_for_triangles(lod, request.triangles) : priority_for_budget(lod, request.triangles);
    case Kind::kPriority:
      if (request.priority > lod.full())
        throw InputError("", "priority " + std::to_string(request.priority) + " is past the octree's " +
                                 std::to_string(lod.full()) + " expansions");
      return request.priority;
    case Kind::kError:
    case Kind::kCamera: break;
  }
  throw InputError("", "the octree offers levels by percent, triangles or priority, not by error or camera; "
                       "use --structure clusters");
}

const LevelCut& LevelExtractor::extract(const LevelRequest& request) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  cut_.structure = structure_;
  cut_.triangles.clear();
  cut_.clusters = 0;
  cut_.priority = 0;
  cut_.error = 0;
  using Kind = LevelRequest::Kind;
  if (structure_ == LodStructure::kOctree) {
    const OctreeLod& o = *model_->octree;
    const std::size_t p = octree_priority(request);
    cut_.select_seconds = std::chrono::duration<double>(clock::now() - start).count();
    extract_lod(o.tree, o.lod, p, &expanded_, &cut_.triangles);
    cut_.priority = p;
    cut_.percent = o.lod.full() ? 100.0 * double(p) / double(o.lod.full()) : 100.0;
  } else {
    const ClusterHierarchy& h = *model_->clusters;
    switch (request.kind) {
      case Kind::kPercent: {
        const double share = std::clamp(request.percent, 0.0, 100.0) / 100.0;
        cut_.error = error_for_triangles(table_, std::int64_t(std::floor(share * double(h.full_triangles))));
        select_clusters_by_error(h, float(cut_.error), &selected_);
        break;
      }
      case Kind::kTriangles:
        cut_.error = request.strict ? error_for_triangles(table_, request.triangles)
                                    : error_for_budget(table_, request.triangles);
        select_clusters_by_error(h, float(cut_.error), &selected_);
        break;
      case Kind::kError:
        cut_.error = request.error;
        select_clusters_by_error(h, float(request.error), &selected_);
        break;
      case Kind::kCamera:
        select_clusters_for_view(h, request.camera, float(request.pixel_error), &projected_, &selected_);
        break;
      case Kind::kPriority:
        throw InputError("", "the cluster hierarchy has no priority numbers; ask by percent, triangles, error or "
                             "camera, or use --structure octree");
    }
    cut_.select_seconds = std::chrono::duration<double>(clock::now() - start).count();
    emit_clusters(h, selected_, &cut_.triangles);
    cut_.clusters = selected_.size();
    cut_.percent = h.full_triangles ? 100.0 * double(cut_.triangles.size()) / double(h.full_triangles) : 100.0;
  }
  cut_.extract_seconds = std::chrono::duration<double>(clock::now() - start).count();
  return cut_;
}

TriangleMesh compact_level(const LodModel& model, const std::vector<Triangle>& triangles) {
  if (model.clusters && model.clusters->paged) return model.clusters->paged->compact(triangles);
  std::vector<Triangle> out = triangles;
  const VertexArray& v = model.vertices;
  TriangleMesh mesh = compact_mesh(v.positions, v.normals, v.colors, {&out});
  mesh.triangles = std::move(out);
  return mesh;
}

Aabb model_bounds(const LodModel& model) {
  if (model.clusters && model.clusters->paged) return model.clusters->paged->bounds();
  return bounds(model.vertices.positions);
}

OctreeSummary describe_octree(const LodModel& model) {
  require_structure(model, LodStructure::kOctree, "");
  const McOctree& t = model.octree->tree;
  const LodArray& lod = model.octree->lod;
  OctreeSummary s;
  s.resolution = t.grid.resolution;
  s.depth = t.depth;
  s.cube_size = t.grid.cube_size;
  s.origin = t.grid.origin;
  s.nodes = t.size();
  s.nodes_per_level.assign(std::size_t(t.depth) + 1, 0);
  for (std::size_t n = 0; n < t.size(); ++n) {
    ++s.nodes_per_level[t.nodes.levels[n]];
    s.leaves += t.is_leaf(n);
  }
  s.expansions = lod.full();
  s.pinned = lod.pinned;
  s.pinned_triangles = lod.accumulated[lod.pinned];
  s.full_triangles = lod.accumulated.back();
  const std::vector<std::size_t> offered = monotone_priorities(lod);
  s.offered_levels = offered.size();
  s.coarsest_triangles = lod.accumulated[offered.front()];
  return s;
}

ClusterSummary describe_clusters(const LodModel& model) {
  require_structure(model, LodStructure::kClusters, "");
  const ClusterHierarchy& h = *model.clusters;
  ClusterSummary s;
  s.clusters = h.size();
  s.groups = h.groups.size();
  s.stored_triangles = h.stored_triangles();
  s.levels = h.levels();
  s.full_triangles = h.full_triangles;
  s.coarsest_triangles = LevelExtractor(model, LodStructure::kClusters).coarsest_triangles();
  return s;
}

std::vector<LevelSummary> summarize_levels(const LodModel& model, LodStructure structure,
                                           const std::vector<double>& percents) {
  LevelExtractor extractor(model, structure);
  std::vector<LevelSummary> out;
  std::vector<std::uint8_t> used(model.vertices.size(), 0);
  for (double percent : percents) {
    const LevelCut& cut = extractor.extract(LevelRequest::at_percent(percent));
    LevelSummary s;
    s.percent = percent;
    s.priority = cut.priority;
    s.error = cut.error;
    s.clusters = cut.clusters;
    s.triangles = cut.triangles.size();
    for (const Triangle& t : cut.triangles)
      for (std::int32_t v : t)
        if (!used[std::size_t(v)]) used[std::size_t(v)] = 1, ++s.vertices;
    for (const Triangle& t : cut.triangles)
      for (std::int32_t v : t) used[std::size_t(v)] = 0;
    out.push_back(s);
  }
  return out;
}

}  // namespace scan2lod
