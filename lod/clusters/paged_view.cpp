#include <scan2lod/lod/clusters/paged_view.h>

#include <scan2lod/lod/clusters/cluster_cut.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace scan2lod {
namespace {

// Coarser by this much a step, until the cut's pages fit.
constexpr double kCoarser = 1.5;
constexpr int kMostSteps = 60;  // 1.5^60: past any model's errors

}  // namespace

PagedView::PagedView(const LodModel& model, const PagedViewOptions& options)
    : model_(model), options_(options), extractor_(model, LodStructure::kClusters) {
  if (!model.clusters || !model.clusters->paged)
    throw std::invalid_argument("PagedView: the model was not opened page by page (open_paged_model)");
  pages_ = model.clusters->paged.get();
  pixel_error_ = options.pixel_error;
  // The coarsest pages first: those whose clusters are drawn at the largest
  // errors, until the pinned share is spent. The page of the top is always
  // pinned, whatever its size, so that some cut is always at hand.
  const ClusterHierarchy& h = *model.clusters;
  std::vector<std::size_t> order(h.pages.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&h](std::size_t a, std::size_t b) {
    return h.pages[a].min_error > h.pages[b].min_error;
  });
  pinned_.assign(h.pages.size(), 0);
  const double share = double(pages_->budget()) * options.pinned_share;
  for (const std::size_t p : order) {
    const bool top = h.pages[p].max_error == std::numeric_limits<float>::infinity();
    if (!top && double(pages_->pinned_bytes() + pages_->page_bytes(p)) > share) break;
    pages_->pin(p);
    pinned_[p] = 1;
  }
}

std::uint64_t PagedView::pages_for(const CameraView& camera, double pixel_error, std::vector<std::size_t>* pages) {
  select_clusters_for_view(*model_.clusters, camera, float(pixel_error), &projected_, &selected_);
  pages->clear();
  for (const std::int32_t c : selected_) {
    const std::size_t p = pages_->page_of(c);
    if (pages->empty() || pages->back() != p) pages->push_back(p);
  }
  std::sort(pages->begin(), pages->end());
  pages->erase(std::unique(pages->begin(), pages->end()), pages->end());
  std::uint64_t bytes = 0;
  for (const std::size_t p : *pages)
    if (!pinned_[p]) bytes += pages_->page_bytes(p);
  return bytes;
}

const LevelCut& PagedView::view(const CameraView& camera) {
  const double left = pages_->budget() > pages_->pinned_bytes() ? double(pages_->budget() - pages_->pinned_bytes()) : 0;
  const auto room = std::uint64_t(left * (1 - options_.prefetch_share));
  double error = options_.pixel_error;
  for (int step = 0; step < kMostSteps && pages_for(camera, error, &needed_) > room; ++step) error *= kCoarser;
  pixel_error_ = error;
  view_clock_ = pages_->clock();
  return extractor_.extract(LevelRequest::for_camera(camera, error));
}

std::size_t PagedView::prefetch(const CameraView& camera) {
  pages_for(camera, pixel_error_, &needed_);
  std::size_t read = 0;
  for (const std::size_t p : needed_) {
    if (pages_->resident(p)) continue;
    if (!pages_->prefetch(p, view_clock_ + 1)) break;
    ++read;
  }
  return read;
}

}  // namespace scan2lod
