// The LOD graphs as VTK charts (vtkChartXY) in one PNG. For the octree, the
// Lee 2007, §6.3: the LOD metric against the priority number (Fig. 6.6) and its
// first 300 priorities (Fig. 6.7), the accumulated triangle count against the
// priority number (Fig. 6.8). For the cluster hierarchy: the uniform cut's
// error threshold, clusters drawn and vertices used against its triangles.
// Given a reference surface, either adds the error of each level against its
// triangle count.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/lod_model.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {

// One level's distance to a reference surface (measure/surface_distance.h).
struct LevelError {
  double percent = 0;
  std::size_t priority = 0;        // octree
  double error = 0;                // clusters: the uniform error threshold
  std::size_t triangles = 0;
  double mean_to_reference = 0;    // level -> reference, % of the reference's diagonal
  double mean_from_reference = 0;  // reference -> level, same unit
};

// Measures the levels at `percents` against `reference`, `samples` points per
// direction (fixed seed: the same numbers every run). Progress on a terminal.
std::vector<LevelError> level_errors(const LodModel& model, LodStructure structure, const TriangleMesh& reference,
                                     const std::vector<double>& percents, std::size_t samples);

struct PlotOptions {
  int chart_width = 520;   // pixels per chart
  int chart_height = 400;
  std::size_t part = 300;  // priorities in the Fig. 6.7 close-up (octree)
  // Fig. 6.6 on a log axis (when most metrics are positive; values under
  // 1e-8 of the largest drawn at that floor). The close-up stays linear.
  bool log_metric = true;
};

// Where each chart sits in the picture (pixels, origin top-left).
struct PlotChart {
  std::string title;
  int x = 0, y = 0, width = 0, height = 0;
};

struct PlotPicture {
  int width = 0, height = 0;
  std::vector<PlotChart> charts;
  std::size_t priorities = 0;      // octree: LOD array entries drawn
  std::int64_t full_triangles = 0; // at full detail
};

// Draws the charts (three, or four with `errors` non-empty: two per row)
// off-screen and writes them to `path` as one PNG (atomically). The first
// series of every chart is drawn in kPlotBlue, the second in kPlotRed.
// Throws InputError without an X display, for a structure the model lacks, or
// when the write fails.
PlotPicture write_lod_plots(const LodModel& model, LodStructure structure, const std::vector<LevelError>& errors,
                            const PlotOptions& options, const std::string& path);

constexpr std::uint8_t kPlotBlue[3] = {31, 119, 180};
constexpr std::uint8_t kPlotRed[3] = {214, 39, 40};

}  // namespace scan2lod
