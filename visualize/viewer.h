// The interactive viewer (`scan2lod view`): one VTK window on a LOD model, a
// mesh or a scan set. On a model a slider (vtkSliderWidget) picks the level of
// one LOD structure (the octree or the cluster hierarchy) by percentage or by
// triangle budget, and every move takes it by reference through the LOD face,
// the triangles `scan2lod extract` gives (LevelSource; for the octree a
// LodCursor that applies only the expansions in between): nothing is
// simplified again. Keys switch the drawing (shaded, wireframe,
// shaded with edges, points, vertex colour), show the octree cells of the
// current cut coloured by level, and split the window into two levels under
// one camera. On the cluster hierarchy, `c` lets the cut follow the camera
// (re-selected at a pixel error, `[` `]`, on every camera change), `f` freezes
// it to inspect it from outside, and `l` colours triangles by DAG level. A scan set shows each range image's oriented points in its own
// colour with its normals as short lines, to check alignment and normals
// before a build.
//
// Everything a user does goes through the interactor and the slider widget,
// and `move_slider`, `press_key` and `run_script` send exactly those events,
// so the viewer can be driven without a human (tests, scripted screenshots).
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/lod_model.h>

#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

class vtkRenderWindowInteractor;
class vtkSliderWidget;

namespace scan2lod {

// What `scan2lod view` was pointed at.
struct ViewerInput {
  enum class Kind { model, mesh, scans } kind = Kind::mesh;
  std::string source;                // the file(s), for the window title and messages
  std::optional<LodModel> model;     // Kind::model
  bool paged = false;                // the model is read page by page (open_paged_model)
  TriangleMesh mesh;                 // Kind::mesh
  std::vector<OrientedPoints> scans; // Kind::scans: one per range image, common frame
  std::vector<std::string> scan_names;
};

// Reads a .mco model, a mesh (.ply with faces, .obj, .off, .stl, .vtp), or a
// scan set (a .conf, range-grid .ply files, organized .pcd files; several
// files are one set). Throws InputError naming the file and what was expected.
// With `cache_bytes`, a model with pages (format 4.6) is opened page by page
// (lod/clusters/paged_model.h): the viewer then holds at most that many bytes of pages
// and starts on the camera cut.
ViewerInput load_viewer_input(const std::vector<std::string>& inputs, std::uint64_t cache_bytes = 0);

struct ViewerOptions {
  int width = 1200, height = 800;  // window pixels
  double percent = 100;            // first level shown
  double compare_percent = 20;     // level in the split view's right half
  // Where `s` saves: this path, or when it exists, NAME_2.png, NAME_3.png, ...
  std::string screenshot = "scan2lod_view.png";
  bool offscreen = false;          // render without showing a window (scripts, tests)
  // A model's levels come from this structure; unset: default_structure.
  std::optional<LodStructure> structure;
};

enum class DrawMode { shaded, wireframe, shaded_edges, points, vertex_colors };
const char* draw_mode_name(DrawMode mode);

// What the window shows now, read back from what VTK was given.
struct ViewerState {
  bool has_levels = false;           // a model: the slider is there
  bool slider_by_triangles = false;  // the slider's unit
  double slider_value = 0;
  LodStructure structure = LodStructure::kOctree;  // where a model's levels come from
  double percent = 100;              // of the level shown: of the LOD array (octree), of the full triangles (clusters)
  std::size_t priority = 0;          // octree: expansions
  double error = 0;                  // clusters: the uniform cut's error threshold (0 for a camera cut)
  std::size_t clusters = 0;          // clusters: drawn
  std::size_t triangles = 0;  // polygons in the displayed poly data
  std::size_t vertices = 0;   // points in the displayed poly data
  double extract_ms = 0;      // taking the last level change's triangles (LevelSource::cut)
  double convert_ms = 0;      // plain mesh -> vtkPolyData
  double render_ms = 0;       // the first render after the change: upload and draw
  DrawMode mode = DrawMode::shaded;
  bool cells = false;           // octree cells shown
  std::size_t cell_count = 0;   // nodes of the cut drawn
  bool split = false;
  double compare_percent = 0;
  std::size_t compare_triangles = 0;
  // Clusters: the view-dependent cut (key c), re-selected for the camera on
  // every camera change unless frozen (key f), at `pixel_error` pixels ([ ]).
  bool camera_cut = false;
  bool frozen = false;
  double pixel_error = 1;
  std::size_t camera_selections = 0;  // cuts chosen for a camera so far
  bool dag_colors = false;      // clusters: triangles coloured by DAG level (key l)
  int levels = 0;               // octree depth + 1, or the DAG's levels
  bool scan_set = false;        // showing oriented points, not a mesh
  bool normals = false;         // scan sets: normal glyphs shown
  std::string overlay;          // the text in the window's corner
  std::string last_screenshot;  // path of the last picture saved
  // A model read page by page: the budget, the page bytes held now and at
  // most, pages read and prefetched so far, and the pixel error the last
  // camera cut took to fit the budget (>= pixel_error).
  bool paged = false;
  std::uint64_t page_budget = 0, page_bytes = 0, peak_page_bytes = 0, pages_read = 0, pages_prefetched = 0;
  double cut_pixel_error = 0;
};

class Viewer {
 public:
  // Builds the window, the actors and (for a model) the slider, at the level
  // options.percent, with the camera framed on the whole object. Throws
  // InputError without an X display (see require_display).
  Viewer(ViewerInput input, const ViewerOptions& options);
  ~Viewer();
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  vtkRenderWindowInteractor* interactor() const;
  vtkSliderWidget* slider() const;  // null unless the input is a model
  ViewerState state() const;

  // Moves the slider to `value` (in its unit) the way a drag ends: the
  // representation's value, then the widget's InteractionEvent; then renders.
  void move_slider(double value);
  // Sets the slider's unit (the `t` key toggles it).
  void set_slider_by_triangles(bool by_triangles);
  // Sends one key through the interactor (KeyPress, Char, KeyRelease) as X
  // would: `keysym` is "o", "s", "Right", "bracketleft", ...; then renders.
  void press_key(const std::string& keysym);
  // Renders and saves the window as a PNG (atomically); returns the path.
  // Empty `path`: the next free name after options.screenshot.
  std::string screenshot(const std::string& path = "");
  // Runs commands, one per line, printing the state after each to `log`:
  //   percent P | triangles T | slider V | key KEYSYM | orbit DEGREES |
  //   zoom FACTOR | screenshot PATH | print
  // (orbit turns the camera about the focal point's up axis, zoom dollies it
  // towards the focal point by FACTOR > 0, as a user's drag would).
  // Blank lines and lines starting with # are skipped. Throws InputError
  // naming `source` and the line for anything else.
  void run_script(std::istream& in, const std::string& source, std::ostream& log);
  // Turns the camera (azimuth, degrees) and dollies it (factor), then renders.
  void move_camera(double azimuth, double dolly);
  // Shows the window and runs the event loop until it is closed (or `q`).
  void start();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// One line: "percent 20 priority 699 triangles 4976 vertices 2493 mode shaded ..."
std::string describe(const ViewerState& state);

}  // namespace scan2lod
