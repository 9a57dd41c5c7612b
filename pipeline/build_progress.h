// One progress for a whole build instead of a bar per stage: the stages'
// own reports (labels "signed distances", "bricks", "clusters", ...) mapped
// onto one fraction by the share of the build each is expected to take, and
// passed on to the installed sink as "build". A terminal turns it into one
// bar with one ETA.
#pragma once

#include <scan2lod/core/progress.h>

#include <map>
#include <string>

namespace scan2lod {

class BuildProgress {
 public:
  // Shares of the build's time, relative to the reconstruction's (1): reading
  // the inputs, the octree's build and the cluster hierarchy's, 0 when not
  // done. Measured on the bunny at R = 256 and 1 M- and 10 M-point scans at
  // R = 1024 and 2048: reading about 0.05, octree about 4, clusters about 1.6.
  BuildProgress(double reading, double octree, double clusters);
  ~BuildProgress();  // reports the build finished and puts the sink back
  BuildProgress(const BuildProgress&) = delete;
  BuildProgress& operator=(const BuildProgress&) = delete;

  // The octree's build reports nothing of its own: marks its start and end.
  void octree_started();
  void octree_finished();

 private:
  void report(double fraction);
  struct Span {
    double start, size;
  };
  ProgressSink outer_;
  std::map<std::string, Span> spans_;
  double octree_start_ = 0, octree_size_ = 0;
  double done_ = 0;
};

}  // namespace scan2lod
