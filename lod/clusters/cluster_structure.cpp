// The cluster hierarchy (Cignoni et al. 2005) behind the LOD face: its cuts by
// percent, triangle budget, error or camera (lod/clusters/cluster_cut.h), its
// record among the registered structures (lod/structure.h), what `info` says
// of it, and adding one to a model.
#include <scan2lod/core/error.h>
#include <scan2lod/lod/clusters/cluster_sections.h>
#include <scan2lod/lod/clusters/cut_refinement.h>
#include <scan2lod/lod/level_budget.h>
#include <scan2lod/lod/structure.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace scan2lod {

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

namespace {

class ClusterLevels final : public StructureLevels {
 public:
  explicit ClusterLevels(const LodModel& model) : model_(model), h_(*model.clusters), table_(cluster_cut_table(h_)) {}

  void select(const LevelRequest& request, LevelCut* cut) override {
    using Kind = LevelRequest::Kind;
    refine_to_ = -1;
    switch (request.kind) {
      case Kind::kPercent: {
        const double share = std::clamp(request.percent, 0.0, 100.0) / 100.0;
        select_by_count(std::int64_t(std::floor(share * double(h_.full_triangles))), true, request.refine, cut);
        break;
      }
      case Kind::kTriangles:
        select_by_count(request.triangles, request.strict, request.refine, cut);
        break;
      case Kind::kError:
        cut->error = request.error;
        select_clusters_by_error(h_, float(request.error), &selected_);
        break;
      case Kind::kCamera:
        select_clusters_for_view(h_, request.camera, float(request.pixel_error), &projected_, &selected_);
        break;
      case Kind::kPriority:
        throw InputError("", "the cluster hierarchy has no priority numbers; ask by percent, triangles, error or "
                             "camera, or use --structure octree");
    }
  }
  void emit(LevelCut* cut) override {
    kept_.clear();
    emit_clusters(h_, selected_, &cut->triangles);
    cut->clusters = selected_.size();
    cut->refined_from = 0;
    if (refine_to_ >= 0) {
      const std::size_t stored = cut->triangles.size();
      const CutRefiner::Result r = refine(&cut->triangles);
      // A refinement that stalled over the budget (handles edge collapse
      // cannot remove) is no better than the stored cut.
      if (r.refined && std::int64_t(cut->triangles.size()) <= ceiling_) {
        cut->refined_from = stored;
        cut->error += r.error;  // deviations add up (the triangle inequality)
      } else {
        // The stored cut the count would get unrefined.
        kept_.clear();
        select_clusters_by_rank(h_, fallback_rank_, &selected_);
        cut->triangles.clear();
        emit_clusters(h_, selected_, &cut->triangles);
        cut->clusters = selected_.size();
        cut->error = cut_error(h_, selected_);
      }
    }
    cut->percent = h_.full_triangles ? 100.0 * double(cut->triangles.size()) / double(h_.full_triangles) : 100.0;
  }
  std::int64_t full_triangles() const override { return h_.full_triangles; }
  std::int64_t coarsest_triangles() const override { return table_.triangles.back(); }
  std::vector<std::int64_t> offered_triangles() const override {
    return {table_.triangles.begin(), table_.triangles.end()};
  }
  int levels() const override { return h_.levels(); }
  // Per triangle, its cluster's DAG level (0 at full detail).
  std::vector<std::uint8_t> triangle_levels(const LevelCut& cut) const override {
    std::vector<std::uint8_t> out;
    out.reserve(kept_.empty() ? cut.triangles.size() : 0);
    for (std::int32_t c : selected_) {
      const Cluster& cl = h_.clusters[std::size_t(c)];
      out.insert(out.end(), cl.triangle_count, cl.level);
    }
    if (kept_.empty()) return out;
    std::vector<std::uint8_t> refined(kept_.size());
    for (std::size_t i = 0; i < kept_.size(); ++i) refined[i] = out[kept_[i]];
    return refined;
  }

 private:
  // A cut by count: a finer stored cut refined to the count where one lies
  // close enough (lod/clusters/cut_refinement.h), else the stored cut the
  // budget rules give (lod/level_budget.h).
  void select_by_count(std::int64_t budget, bool strict, bool refine, LevelCut* cut) {
    const float stored = strict ? rank_for_triangles(table_, budget) : rank_for_budget(table_, budget);
    const float finer = refine ? rank_to_refine(table_, budget) : -1.f;
    if (finer >= 0) {
      refine_to_ = budget;
      ceiling_ = budget_ceiling(budget, strict);
      fallback_rank_ = stored;
    }
    select_clusters_by_rank(h_, finer >= 0 ? finer : stored, &selected_);
    cut->error = cut_error(h_, selected_);
  }

  // The emitted cut refined to refine_to_, over the model's vertices or, for
  // a model read page by page, the pages' (then numbered as the model's).
  CutRefiner::Result refine(std::vector<Triangle>* triangles) {
    const std::size_t target = std::size_t(refine_to_);
    if (!h_.paged) {
      const VertexArray& v = model_.vertices;
      return refiner_.refine({v.positions, v.normals, v.colors}, triangles, target, &kept_);
    }
    return refiner_.refine_pages(*h_.paged, triangles, target, &kept_);
  }

  const LodModel& model_;
  const ClusterHierarchy& h_;
  ClusterCutTable table_;
  std::vector<float> projected_;
  std::vector<std::int32_t> selected_;
  CutRefiner refiner_;
  std::int64_t refine_to_ = -1;   // the count the selected cut is refined to; -1: not refined
  std::int64_t ceiling_ = 0;      // the most triangles the refined cut may keep
  float fallback_rank_ = -1;      // the stored cut's, should the refinement stall above that
  std::vector<std::uint32_t> kept_;  // per triangle of a refined cut, which it was
};

StructureInfo cluster_info(const LodModel& model, const std::vector<double>& percents) {
  const ClusterSummary c = describe_clusters(model);
  const auto lods = summarize_levels(model, LodStructure::kClusters, percents);
  StructureInfo info;
  nlohmann::ordered_json levels = nlohmann::ordered_json::array();
  for (const LevelSummary& l : lods)
    levels.push_back({{"percent", l.percent}, {"error", l.error}, {"clusters", l.clusters},
                      {"triangles", l.triangles}, {"vertices", l.vertices}});
  info.json = {{"clusters", c.clusters},
               {"groups", c.groups},
               {"levels", c.levels},
               {"full_triangles", c.full_triangles},
               {"stored_triangles", c.stored_triangles},
               {"coarsest_triangles", c.coarsest_triangles},
               {"levels_of_detail", levels}};
  info.say("\nclusters: %zu clusters in %zu groups over %d levels; %zu triangles stored (%.2fx the full "
           "mesh's %lld); the coarsest cut has %lld\n",
           c.clusters, c.groups, c.levels, c.stored_triangles,
           c.full_triangles ? double(c.stored_triangles) / double(c.full_triangles) : 0.0,
           static_cast<long long>(c.full_triangles), static_cast<long long>(c.coarsest_triangles));
  info.say("\n%6s %10s %10s %10s %10s\n", "LOD %", "error", "clusters", "triangles", "vertices");
  for (const LevelSummary& l : lods)
    info.say("%6g %10.3g %10zu %10zu %10zu\n", l.percent, l.error, l.clusters, l.triangles, l.vertices);
  return info;
}

}  // namespace

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

const StructureKind& cluster_structure() {
  static const StructureKind kind{
      LodStructure::kClusters,
      "clusters",
      "the cluster hierarchy",
      "cluster-hierarchy",
      3,
      [](const LodModel& model) { return model.clusters.has_value(); },
      [](const LodModel& model) -> std::unique_ptr<StructureLevels> {
        return std::make_unique<ClusterLevels>(model);
      },
      []() -> std::unique_ptr<StructureSections> { return std::make_unique<ClusterSections>(); },
      cluster_info,
  };
  return kind;
}

}  // namespace scan2lod
