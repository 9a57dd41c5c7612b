// The LOD graphs of the seed's §6.3 as VTK charts (vtkChartXY) in one PNG:
// the LOD metric against the priority number (Fig. 6.6) and its first 300
// priorities (Fig. 6.7), the accumulated triangle count against the priority
// number (Fig. 6.8), and, given a reference surface, the error of each level
// against its triangle count.
#pragma once

#include "core/types.h"
#include "lod/model_file.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {

// One level's distance to a reference surface (measure/surface_distance.h).
struct LevelError {
  double percent = 0;
  std::size_t priority = 0, triangles = 0;
  double mean_to_reference = 0;    // level -> reference, % of the reference's diagonal
  double mean_from_reference = 0;  // reference -> level, same unit
};

// Measures the levels at `percents` against `reference`, `samples` points per
// direction (fixed seed: the same numbers every run). Progress on a terminal.
std::vector<LevelError> level_errors(const LodModel& model, const TriangleMesh& reference,
                                     const std::vector<double>& percents, std::size_t samples);

struct PlotOptions {
  int chart_width = 520;   // pixels per chart
  int chart_height = 400;
  std::size_t part = 300;  // priorities in the Fig. 6.7 close-up
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
};

// Draws the charts (three, or four with `errors` non-empty: two per row)
// off-screen and writes them to `path` as one PNG (atomically). The first
// series of every chart is drawn in kPlotBlue, the second in kPlotRed.
// Throws InputError without an X display or when the write fails.
PlotPicture write_lod_plots(const LodModel& model, const std::vector<LevelError>& errors, const PlotOptions& options,
                            const std::string& path);

constexpr std::uint8_t kPlotBlue[3] = {31, 119, 180};
constexpr std::uint8_t kPlotRed[3] = {214, 39, 40};

}  // namespace scan2lod
