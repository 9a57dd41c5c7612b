// What a viewer draws of a model read page by page (lod/clusters/paged_model.h),
// within the page budget, however the camera moves:
// - the coarsest pages stay resident (pinned), so that every view has a
//   cut to fall back on;
// - each view is the camera cut at the pixel error asked for when its pages
//   fit the budget beside the pinned ones and the prefetch share, else at
//   the least coarser error (in steps of 1.5x) whose pages do;
// - between frames, prefetch() reads the pages a camera about to move will
//   need, dropping only pages the current view does not draw, as El-Sana and
//   Chiang prefetch the nodes of a view-dependence tree (*External Memory
//   View-Dependent Simplification*, 2000).
#pragma once

#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/lod_model.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

struct PagedViewOptions {
  double pixel_error = 1;      // asked for; coarser only where the budget needs it
  double pinned_share = 0.25;  // of the budget, at most, for the coarsest pages
  // Of what is left, kept for prefetching: a view whose pages filled the
  // budget would leave no room to read ahead.
  double prefetch_share = 0.25;
};

class PagedView {
 public:
  // `model` from open_paged_model (its hierarchy has `paged`), kept by
  // reference. Pins the coarsest pages, reading them now.
  PagedView(const LodModel& model, const PagedViewOptions& options = {});

  // The cut for `camera`, read page by page.
  const LevelCut& view(const CameraView& camera);
  // The pixel error the last view was cut at (>= options.pixel_error).
  double pixel_error() const { return pixel_error_; }
  // Reads the pages `camera` would need that are not held, while they fit
  // beside the last view's and the pinned ones. Returns pages read.
  std::size_t prefetch(const CameraView& camera);

  const ClusterPages& pages() const { return *pages_; }
  const LevelExtractor& extractor() const { return extractor_; }

 private:
  // The pages the cut of `camera` at `pixel_error` draws, and their bytes
  // not already pinned.
  std::uint64_t pages_for(const CameraView& camera, double pixel_error, std::vector<std::size_t>* pages);

  const LodModel& model_;
  ClusterPages* pages_;
  PagedViewOptions options_;
  LevelExtractor extractor_;
  double pixel_error_ = 1;
  std::uint64_t view_clock_ = 0;  // page uses since then belong to the last view
  std::vector<float> projected_;
  std::vector<std::int32_t> selected_;
  std::vector<std::size_t> needed_;
  std::vector<std::uint8_t> pinned_;
};

}  // namespace scan2lod
