// Off-screen montage of levels of detail, laid out like Lee 2007's Figs.
// 6.3-6.5: one row per level, wireframe beside shaded (or one mode, levels side
// by side), every panel through the same camera and captioned with its LOD %,
// triangles and vertices.
#pragma once

#include <scan2lod/lod/lod_model.h>
#include <scan2lod/visualize/scene.h>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace scan2lod {

enum class RenderMode { shaded, wireframe, both };

// Throws InputError for anything but "shaded", "wireframe" or "both".
RenderMode parse_render_mode(const std::string& text);

struct MontageOptions {
  int panel_width = 400;   // pixels per panel
  int panel_height = 400;
  RenderMode mode = RenderMode::both;
  // Camera turn (degrees) from the default view down -z with +y up, applied
  // before framing on the whole model's box.
  double azimuth = 0;
  double elevation = 0;
  // A camera given in full instead (azimuth and elevation then unused), in
  // the inputs' frame (the model's origin added, as a tileset's frame is).
  std::optional<ViewCamera> camera;
  bool captions = true;  // each panel's LOD %, triangles and vertices
};

// Where one panel sits in the picture (pixels, origin top-left) and what it shows.
struct MontagePanel {
  int x = 0, y = 0, width = 0, height = 0;
  RenderMode mode = RenderMode::shaded;  // shaded or wireframe
  double percent = 0;                    // as asked
  std::size_t priority = 0;              // octree: expansions
  double error = 0;                      // clusters: the uniform error threshold
  std::size_t clusters = 0;              // clusters: drawn
  std::size_t triangles = 0, vertices = 0;
};

struct Montage {
  int width = 0, height = 0;
  std::vector<MontagePanel> panels;  // level by level; wireframe first in a row
};

// Renders the levels of `structure` at `percents` off-screen into one PNG at `path` (written
// atomically). Throws InputError for a bad size, an empty list, no X display
// (see require_display), a structure the model lacks, or a failed write.
// Progress on a terminal.
Montage render_montage(const LodModel& model, LodStructure structure, const std::vector<double>& percents,
                       const MontageOptions& options, const std::string& path);

// Parses "WxH" (e.g. 400x300) into positive pixel counts up to 8192.
// Throws InputError naming `flag` otherwise.
void parse_size(const std::string& text, const std::string& flag, int* width, int* height);

}  // namespace scan2lod
