#include <scan2lod/pipeline/build_progress.h>

#include <algorithm>

namespace scan2lod {

BuildProgress::BuildProgress(double reading, double octree, double clusters) : outer_(progress_sink()) {
  if (!outer_) return;
  const double total = reading + 1.0 + octree + clusters;
  const double r = 1.0 / total, r0 = reading / total;
  spans_["reading inputs"] = {0.0, r0};
  // Within the reconstruction: distances are most of it, in core or in bricks.
  spans_["signed distances"] = {r0, 0.75 * r};
  spans_["marching cubes"] = {r0 + 0.75 * r, 0.1 * r};
  spans_["pieces and holes"] = {r0 + 0.85 * r, 0.15 * r};
  spans_["bricks"] = {r0, 0.85 * r};
  octree_start_ = r0 + r;
  octree_size_ = octree / total;
  spans_["clusters"] = {r0 + r + octree_size_, clusters / total};
  set_progress_sink([this](const std::string& label, double fraction, bool) {
    const auto it = spans_.find(label);
    if (it != spans_.end()) report(it->second.start + fraction * it->second.size);
  });
}

BuildProgress::~BuildProgress() {
  if (!outer_) return;
  set_progress_sink(outer_);
  outer_("build", 1.0, true);
}

void BuildProgress::octree_started() { report(octree_start_); }
void BuildProgress::octree_finished() { report(octree_start_ + octree_size_); }

void BuildProgress::report(double fraction) {
  if (!outer_) return;
  // Stage shares are estimates: the build only moves forward.
  done_ = std::max(done_, std::min(fraction, 1.0));
  outer_("build", done_, false);
}

}  // namespace scan2lod
