// Reading a model page by page (lod/clusters/paged_model.h, lod/clusters/paged_view.h):
//   cuts      camera cuts at 1 px from near to far, each read cold: the cut's
//             own bytes (its triangles and vertices as a mesh) against the
//             bytes of the pages read for it (the target: at most 3x);
//   first     the model framed as the viewer opens it: bytes read (records
//             and pages) against the file's (the target: at most 1/20), and
//             the time to that view against load_model's of the whole file,
//             the peer, in the same run;
//   orbit     a viewer (PagedView) circling the model near and far with
//             --cache: the most page bytes held against the budget, views
//             the budget coarsened, pages prefetched.
//
//   scan2lod_bench_pages MODEL.mco [--cache 256M] [--height 1080] [--no-peer]
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/clusters/paged_view.h>
#include <scan2lod/lod/model_file.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <string>

using namespace scan2lod;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

double mb(double bytes) { return bytes / 1e6; }

CameraView camera_at(const Aabb& box, double distance, double azimuth, int height) {
  CameraView c;
  const Vec3f centre = 0.5f * (box.min + box.max);
  c.target = centre;
  c.eye = centre + Vec3f(float(distance * std::sin(azimuth)), 0.15f * float(distance), float(distance * std::cos(azimuth)));
  c.fov_degrees = 30;
  c.height = height;
  return c;
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s MODEL.mco [--cache 256M] [--height 1080] [--no-peer]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[1];
  double cache = 256.0 * 1024 * 1024;
  int height = 1080;
  bool peer = true;
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--cache") && i + 1 < argc) {
      char* unit = nullptr;
      cache = std::strtod(argv[++i], &unit);
      if (*unit == 'K') cache *= 1024;
      if (*unit == 'M') cache *= 1024 * 1024;
      if (*unit == 'G') cache *= 1024.0 * 1024 * 1024;
    } else if (!std::strcmp(argv[i], "--height") && i + 1 < argc) {
      height = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--no-peer")) {
      peer = false;
    }
  }
  const double file = double(std::filesystem::file_size(path));
  const auto budget = std::uint64_t(cache);

  // First view, cold (the page cache of the system is not dropped: both
  // ways read from it alike).
  auto start = std::chrono::steady_clock::now();
  std::optional<LodModel> paged = open_paged_model(path, budget);
  if (!paged) {
    std::fprintf(stderr, "%s has no pages (no cluster hierarchy, or written before format 4.6)\n", path.c_str());
    return 1;
  }
  const double open_seconds = seconds_since(start);
  const Aabb box = model_bounds(*paged);
  const double radius = 0.5 * double(box.diagonal());
  const double framed = 0.8 * radius / std::sin(15.0 * M_PI / 180.0);
  const ClusterHierarchy& h = *paged->clusters;
  std::printf("model %s: %.1f MB, %lld full-detail triangles, %llu stored, %zu pages; cache %.0f MiB\n\n",
              path.c_str(), mb(file), (long long)h.full_triangles, (unsigned long long)h.stored_triangles(),
              h.pages.size(), cache / 1048576);
  {
    LevelExtractor extractor(*paged, LodStructure::kClusters);
    const LevelCut& cut = extractor.extract(LevelRequest::for_camera(camera_at(box, framed, 0, height), 1.0));
    const TriangleMesh mesh = compact_level(*paged, cut.triangles);
    const double first_seconds = seconds_since(start);
    const PageStats& s = h.paged->stats();
    const double read = double(s.head_bytes + s.page_bytes_read);
    std::printf("first view (framed, 1 px at %d px): %zu triangles; read %.2f MB (records %.2f, %llu pages %.2f) = "
                "1/%.0f of the file; %.3f s (open %.3f s)\n",
                height, mesh.triangles.size(), mb(read), mb(double(s.head_bytes)), (unsigned long long)s.pages_read,
                mb(double(s.page_bytes_read)), file / read, first_seconds, open_seconds);
    if (peer) {
      start = std::chrono::steady_clock::now();
      const LodModel whole = load_model(path);
      LevelExtractor whole_extractor(whole, LodStructure::kClusters);
      const LevelCut& whole_cut = whole_extractor.extract(LevelRequest::for_camera(camera_at(box, framed, 0, height), 1.0));
      const TriangleMesh whole_mesh = compact_level(whole, whole_cut.triangles);
      const double whole_seconds = seconds_since(start);
      std::printf("peer, load_model then the same view: %.3f s (%zu triangles): page by page is %.1fx faster\n",
                  whole_seconds, whole_mesh.triangles.size(), whole_seconds / first_seconds);
    }
  }

  std::printf("\n| camera distance (radii) | cut triangles | cut bytes (MB) | pages read | page bytes (MB) | read / cut |\n"
              "|---:|---:|---:|---:|---:|---:|\n");
  double worst = 0;
  for (const double d : {0.6, 1.0, 1.5, 2.5, 4.0, 8.0}) {
    std::optional<LodModel> cold = open_paged_model(path, ~std::uint64_t(0));
    LevelExtractor extractor(*cold, LodStructure::kClusters);
    const LevelCut& cut = extractor.extract(LevelRequest::for_camera(camera_at(box, d * radius, 0.7, height), 1.0));
    const TriangleMesh mesh = compact_level(*cold, cut.triangles);
    const double own = double(mesh.triangles.size()) * 12 +
                       double(mesh.positions.size()) * (12 + (mesh.normals.empty() ? 0 : 12) + (mesh.colors.empty() ? 0 : 3));
    const PageStats& s = cold->clusters->paged->stats();
    worst = std::max(worst, double(s.page_bytes_read) / own);
    std::printf("| %.1f | %zu | %.2f | %llu | %.2f | %.2f |\n", d, mesh.triangles.size(), mb(own),
                (unsigned long long)s.pages_read, mb(double(s.page_bytes_read)), double(s.page_bytes_read) / own);
  }
  std::printf("worst read / cut: %.2f\n", worst);

  // The orbit: 72 views, near and far in turn, prefetching the next.
  PagedView view(*paged);
  const ClusterPages& pages = view.pages();
  int coarsened = 0;
  std::size_t prefetched = 0, triangles = 0;
  double most_error = 1, view_seconds = 0;
  const std::uint64_t pages_before = pages.stats().pages_read;
  for (int i = 0; i < 72; ++i) {
    const auto at = [&](int k) { return camera_at(box, (k / 6) % 2 ? 0.8 * radius : framed, 0.26 * k, height); };
    const auto t = std::chrono::steady_clock::now();
    const LevelCut& cut = view.view(at(i));
    view_seconds += seconds_since(t);
    triangles = std::max(triangles, cut.triangles.size());
    if (view.pixel_error() > 1.0) ++coarsened, most_error = std::max(most_error, view.pixel_error());
    prefetched += view.prefetch(at(i + 1));
  }
  const PageStats& s = pages.stats();
  std::printf("\norbit of 72 views at %.0f MiB: most held %.1f MiB (%.0f %% of the budget; pinned %.1f MiB); "
              "%d views coarsened (to %.2f px at most); %llu pages read, %zu of them prefetched; largest cut %zu "
              "triangles; %.1f ms a view\n",
              cache / 1048576, double(s.peak_resident_bytes) / 1048576, 100.0 * double(s.peak_resident_bytes) / cache,
              double(pages.pinned_bytes()) / 1048576, coarsened, most_error,
              (unsigned long long)(s.pages_read - pages_before), prefetched, triangles, 1e3 * view_seconds / 72);
  return s.peak_resident_bytes <= budget ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "scan2lod_bench_pages: %s\n", e.what());
  return 1;
}
