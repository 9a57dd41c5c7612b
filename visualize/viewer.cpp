#include <scan2lod/visualize/viewer.h>

#include <scan2lod/acquisition/lattice_normals.h>
#include <scan2lod/acquisition/scan_set.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/mesh_edges.h>
#include <scan2lod/io/file_extension.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/clusters/paged_view.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/visualize/levels.h>
#include <scan2lod/visualize/octree_cells.h>
#include <scan2lod/visualize/png_output.h>
#include <scan2lod/visualize/poly_data.h>
#include <scan2lod/visualize/scene.h>

#include <vtkActor.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkCoordinate.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkProperty2D.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSliderRepresentation2D.h>
#include <vtkSliderWidget.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <istream>
#include <ostream>
#include <sstream>
#include <cstring>

namespace scan2lod {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// A .ply is a scan when its header declares a range grid (as acquisition/ reads it).
bool ply_is_range_grid(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  for (int i = 0; i < 64 && std::getline(in, line); ++i) {
    if (line.rfind("element range_grid", 0) == 0) return true;
    if (line.rfind("end_header", 0) == 0) break;
  }
  return false;
}

// Ten colours that stay apart (Tableau 10), one per scan.
const Rgb kScanColors[10] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},  {148, 103, 189},
                             {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};

}  // namespace

const char* draw_mode_name(DrawMode mode) {
  switch (mode) {
    case DrawMode::shaded: return "shaded";
    case DrawMode::wireframe: return "wireframe";
    case DrawMode::shaded_edges: return "shaded+edges";
    case DrawMode::points: return "points";
    case DrawMode::vertex_colors: return "vertex-colours";
  }
  return "?";
}

ViewerInput load_viewer_input(const std::vector<std::string>& inputs, std::uint64_t cache_bytes) {
  if (inputs.empty()) throw InputError("", "view needs a model (.mco), a mesh or a scan set");
  ViewerInput in;
  for (const std::string& s : inputs) in.source += (in.source.empty() ? "" : " ") + s;
  const std::string ext = lower_extension(inputs[0]);
  bool scans = inputs.size() > 1 || ext == ".conf" || ext == ".pcd";
  if (ext == ".mco") {
    if (inputs.size() > 1) throw InputError(inputs[1], "view takes one .mco model at a time");
    in.kind = ViewerInput::Kind::model;
    if (cache_bytes > 0)
      if (std::optional<LodModel> paged = open_paged_model(inputs[0], cache_bytes)) {
        in.model.emplace();
        std::swap(*in.model, *paged);
        in.paged = true;
        return in;
      }
    in.model = load_model(inputs[0]);
    return in;
  }
  if (!scans && ext == ".ply") {
    if (!std::filesystem::exists(inputs[0])) throw InputError(inputs[0], "no such file");
    scans = ply_is_range_grid(inputs[0]);
  }
  if (!scans) {
    if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl" && ext != ".vtp" && ext != ".glb" &&
        ext != ".gltf")
      throw InputError(inputs[0], "view expects a model (.mco), a mesh (.ply .obj .off .stl .vtp .glb .gltf) or a scan set "
                                  "(.conf, range-grid .ply, organized .pcd), got extension '" + ext + "'");
    in.kind = ViewerInput::Kind::mesh;
    in.mesh = read_mesh(inputs[0]);
    return in;
  }
  in.kind = ViewerInput::Kind::scans;
  for (const PlacedScan& s : read_scan_set(inputs)) {
    in.scans.push_back(range_image_to_points(s.image, s.pose));
    in.scan_names.push_back(std::filesystem::path(s.image.source).filename().string());
  }
  return in;
}

std::string describe(const ViewerState& s) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(2);
  const bool clusters = s.has_levels && s.structure == LodStructure::kClusters;
  if (s.has_levels) {
    out << "percent " << s.percent << ' ';
    if (clusters) {
      char e[40];
      std::snprintf(e, sizeof e, "%.4g", s.error);
      out << "error " << e << " clusters " << s.clusters << ' ';
    } else {
      out << "priority " << s.priority << ' ';
    }
  }
  if (s.scan_set) {
    out << "points " << s.vertices << " normals " << (s.normals ? "on" : "off");
    return out.str();
  }
  out << "triangles " << s.triangles << " vertices " << s.vertices << " mode " << draw_mode_name(s.mode)
      << " cells " << (s.cells ? std::to_string(s.cell_count) : std::string("off")) << " split "
      << (s.split ? std::to_string(s.compare_triangles) : std::string("off"));
  if (s.has_levels) {
    out << " slider " << (s.slider_by_triangles ? "triangles " : "percent ") << s.slider_value << " structure "
        << structure_name(s.structure);
  }
  if (clusters) {
    out << " camera " << (s.camera_cut ? (s.frozen ? "frozen" : "live") : "off") << " pixel-error " << s.pixel_error
        << " selections " << s.camera_selections << " dag-colours " << (s.dag_colors ? "on" : "off");
  }
  if (s.paged) {
    out << " pages-held " << s.page_bytes << " peak " << s.peak_page_bytes << " budget " << s.page_budget
        << " pages-read " << s.pages_read << " prefetched " << s.pages_prefetched << " cut-pixel-error "
        << s.cut_pixel_error;
  }
  return out.str();
}

// The trackball camera, with the viewer's own keys in front of VTK's.
class ViewerStyle : public vtkInteractorStyleTrackballCamera {
 public:
  static ViewerStyle* New();
  vtkTypeMacro(ViewerStyle, vtkInteractorStyleTrackballCamera);
  Viewer::Impl* viewer = nullptr;
  void OnChar() override;
  void OnKeyPress() override;
};
vtkStandardNewMacro(ViewerStyle);

struct Viewer::Impl {
  ViewerInput input;
  ViewerOptions options;
  std::optional<LevelSource> source;          // the main view's levels
  std::optional<LevelSource> compare_source;  // the split view's (so the main cut's DAG levels stay)
  std::optional<PagedView> paged_view;        // a model read page by page: its camera cuts
  ViewerState state;
  Aabb box;

  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderWindowInteractor> interactor;
  vtkNew<ViewerStyle> style;
  vtkNew<vtkRenderer> main;
  vtkNew<vtkRenderer> compare;
  vtkNew<vtkCamera> camera;
  vtkNew<vtkPolyDataMapper> mesh_mapper;
  vtkNew<vtkActor> mesh_actor;
  vtkNew<vtkPolyDataMapper> compare_mapper;
  vtkNew<vtkActor> compare_actor;
  vtkNew<vtkPolyDataMapper> cells_mapper;
  vtkNew<vtkActor> cells_actor;
  vtkNew<vtkLookupTable> level_colors;  // octree cells by level: coarse blue to fine red
  vtkNew<vtkLookupTable> dag_colors;    // triangles by DAG level: coarse (high) blue to fine (0) red
  vtkNew<vtkScalarBarActor> level_legend;
  vtkNew<vtkTextActor> overlay;
  vtkNew<vtkTextActor> compare_overlay;
  vtkNew<vtkTextActor> help;
  std::vector<vtkSmartPointer<vtkActor>> normal_actors;
  vtkSmartPointer<vtkSliderWidget> slider;
  vtkNew<vtkCallbackCommand> slider_moved;
  bool rendering_after_change = false;
  vtkSmartPointer<vtkPolyData> level_poly;  // a model: all vertices, the level's triangles
  double edge_pixels = 8;                    // the level's mean edge length on screen, about
  std::vector<std::uint8_t> vertex_used;
  std::size_t level_vertices = 0;
  bool shown_uniform = false;  // the level shown is a slider's (not a camera's) cut
  vtkNew<vtkCallbackCommand> main_render_started;
  CameraView last_view;        // the camera the camera cut was last chosen for
  bool have_view = false;
  CameraView before_last_view;  // paged: the one before, to guess the next one from
  bool have_before = false;
  Clock::time_point render_start;

  Impl(ViewerInput in, const ViewerOptions& o) : input(std::move(in)), options(o) {}

  void build();
  void show_level(const LevelRequest& request);
  void show_cut(const LevelCut& cut);
  LevelRequest slider_request(double value) const;
  CameraView camera_view() const;
  void select_for_camera(const CameraView& view);
  void on_main_render();
  void set_camera_cut(bool on);
  void show_compare();
  void apply_mode();
  void update_cells();
  void update_overlay();
  void reset_camera();
  void set_split(bool on);
  void set_slider_unit(bool by_triangles);
  void on_slider();
  bool key(const std::string& keysym);  // true when the viewer took the key
  std::string next_screenshot_path() const;
  std::string save(const std::string& path);
  vtkNew<vtkCallbackCommand> render_started, render_ended;
  // Every render goes through the window (the slider widget renders a drag
  // itself), so the first render after a level change is timed by observers.
  void render() { window->Render(); }
};

void ViewerStyle::OnChar() {
  const char* sym = GetInteractor()->GetKeySym();
  std::string keysym = sym ? sym : "";
  if (keysym.empty() || keysym.size() > 1) {
    const char code = GetInteractor()->GetKeyCode();
    if (code) keysym = std::string(1, code);
  }
  const bool arrow = keysym == "Left" || keysym == "Right" || keysym == "Up" || keysym == "Down";
  if (arrow) return;  // taken in OnKeyPress: X sends arrows as both
  if (viewer && viewer->key(keysym)) return;
  // VTK's own keys stay (q/e quit, f fly to, p pick, ...), but not the ones
  // the viewer took or would fight with (j/t joystick: this is a trackball).
  if (keysym == "j" || keysym == "t" || keysym == "3" || keysym == "w" || keysym == "s" || keysym == "r") return;
  vtkInteractorStyleTrackballCamera::OnChar();
}

void ViewerStyle::OnKeyPress() {
  const char* sym = GetInteractor()->GetKeySym();
  const std::string keysym = sym ? sym : "";
  if (viewer && (keysym == "Left" || keysym == "Right" || keysym == "Up" || keysym == "Down")) viewer->key(keysym);
  vtkInteractorStyleTrackballCamera::OnKeyPress();
}

void Viewer::Impl::build() {
  window->SetSize(options.width, options.height);
  window->SetWindowName(("scan2lod view: " + input.source).c_str());
  window->SetMultiSamples(0);
  if (options.offscreen) window->SetOffScreenRendering(1);
  main->SetBackground(1, 1, 1);
  compare->SetBackground(0.97, 0.97, 0.97);
  main->SetActiveCamera(camera);
  compare->SetActiveCamera(camera);  // the split view's linked cameras: one camera
  window->AddRenderer(main);
  render_started->SetClientData(this);
  render_started->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
    auto* v = static_cast<Viewer::Impl*>(self);
    if (v->rendering_after_change) v->render_start = Clock::now();
  });
  render_ended->SetClientData(this);
  render_ended->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
    auto* v = static_cast<Viewer::Impl*>(self);
    if (!v->rendering_after_change) return;
    v->state.render_ms = ms_since(v->render_start);
    v->rendering_after_change = false;
  });
  window->AddObserver(vtkCommand::StartEvent, render_started);
  window->AddObserver(vtkCommand::EndEvent, render_ended);
  interactor->SetRenderWindow(window);
  style->viewer = this;
  style->SetDefaultRenderer(main);
  interactor->SetInteractorStyle(style);

  overlay->GetTextProperty()->SetFontSize(16);
  overlay->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
  overlay->GetTextProperty()->SetVerticalJustificationToTop();
  overlay->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  overlay->GetPositionCoordinate()->SetValue(0.01, 0.985);
  main->AddViewProp(overlay);
  compare_overlay->GetTextProperty()->ShallowCopy(overlay->GetTextProperty());
  compare_overlay->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  compare_overlay->GetPositionCoordinate()->SetValue(0.01, 0.985);
  compare->AddViewProp(compare_overlay);
  help->GetTextProperty()->SetFontSize(12);
  help->GetTextProperty()->SetColor(0.35, 0.35, 0.35);
  help->GetTextProperty()->SetJustificationToRight();
  help->GetTextProperty()->SetVerticalJustificationToTop();
  help->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  help->GetPositionCoordinate()->SetValue(0.99, 0.985);
  main->AddViewProp(help);

  if (input.kind == ViewerInput::Kind::scans) {
    std::size_t total = 0;
    float spacing = 0;
    std::size_t spaced = 0;
    for (const OrientedPoints& p : input.scans) {
      total += p.size();
      for (std::size_t i = 0; i < p.spacing.size(); i += 97) spacing += p.spacing[i], ++spaced;
      for (const Vec3f& q : p.positions) box.extend(q);
    }
    // Short enough to tell a flipped normal at a glance, sparse enough not to
    // hide the points: about 20 000 glyphs in all.
    const float glyph = spaced ? 2.f * spacing / float(spaced) : 0.005f * box.diagonal();
    const std::size_t stride = std::max<std::size_t>(1, total / 20000);
    for (std::size_t s = 0; s < input.scans.size(); ++s) {
      const Rgb& c = kScanColors[s % 10];
      vtkNew<vtkPolyDataMapper> pm;
      pm->SetInputData(points_to_poly_data(input.scans[s], c));
      vtkNew<vtkActor> pa;
      pa->SetMapper(pm);
      pa->GetProperty()->SetPointSize(2);
      pa->GetProperty()->LightingOff();
      main->AddActor(pa);
      const Rgb dark = {Rgb::value_type(c[0] * 2 / 3), Rgb::value_type(c[1] * 2 / 3), Rgb::value_type(c[2] * 2 / 3)};
      vtkNew<vtkPolyDataMapper> nm;
      nm->SetInputData(normals_to_poly_data(input.scans[s], glyph, stride, dark));
      auto na = vtkSmartPointer<vtkActor>::New();
      na->SetMapper(nm);
      na->GetProperty()->LightingOff();
      main->AddActor(na);
      normal_actors.push_back(na);
      // The scan's name in its colour, down the left side.
      vtkNew<vtkTextActor> name;
      name->SetInput(input.scan_names[s].c_str());
      name->GetTextProperty()->SetFontSize(14);
      name->GetTextProperty()->SetColor(c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
      name->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
      name->GetPositionCoordinate()->SetValue(0.01, 0.86 - 0.035 * double(s));
      main->AddViewProp(name);
    }
    state.normals = true;
    state.scan_set = true;
    state.vertices = total;
    state.mode = DrawMode::points;
    help->SetInput("n normals   r reset   s screenshot   q quit");
  } else {
    mesh_actor->SetMapper(mesh_mapper);
    main->AddActor(mesh_actor);
    compare_actor->SetMapper(compare_mapper);
    compare_actor->SetProperty(mesh_actor->GetProperty());  // one look for both halves
    compare->AddActor(compare_actor);
    apply_mode();
    if (input.kind == ViewerInput::Kind::mesh) {
      box = bounds(input.mesh.positions);
      mesh_mapper->SetInputData(mesh_to_poly_data(input.mesh));
      help->SetInput("1 shaded  2 wireframe  3 edges  4 points  5 colours\nr reset   s screenshot   q quit");
    } else {
      const LodModel& model = *input.model;
      const LodStructure structure = options.structure.value_or(default_structure(model));
      require_structure(model, structure, input.source);
      source.emplace(model, structure);
      compare_source.emplace(model, structure);
      state.has_levels = true;
      state.structure = structure;
      state.levels = source->levels();
      if (input.paged) {
        // Read page by page: each cut brings its own vertices (show_cut).
        paged_view.emplace(model);
        state.paged = true;
        state.page_budget = model.clusters->paged->budget();
      } else {
        // Every level's vertices, once: points, normals and colours for VTK.
        TriangleMesh vertices;
        vertices.positions.assign(model.vertices.positions.begin(), model.vertices.positions.end());
        vertices.normals.assign(model.vertices.normals.begin(), model.vertices.normals.end());
        vertices.colors.assign(model.vertices.colors.begin(), model.vertices.colors.end());
        level_poly = mesh_to_poly_data(vertices);
        vertex_used.assign(vertices.positions.size(), 0);
        mesh_mapper->SetInputData(level_poly);
      }
      box = model_bounds(model);
      const int top = std::max(state.levels - 1, 1);
      level_colors->SetNumberOfTableValues(top + 1);
      level_colors->SetHueRange(0.66, 0.0);  // coarse blue (root, level 0) to fine red
      level_colors->SetTableRange(0, top);
      level_colors->Build();
      dag_colors->SetNumberOfTableValues(top + 1);
      dag_colors->SetHueRange(0.0, 0.66);  // fine red (DAG level 0) to coarse blue (the top)
      dag_colors->SetTableRange(0, top);
      dag_colors->Build();
      cells_mapper->SetLookupTable(level_colors);
      cells_mapper->SetScalarModeToUseCellData();
      cells_mapper->SetScalarRange(0, top);
      cells_actor->SetMapper(cells_mapper);
      cells_actor->GetProperty()->LightingOff();
      cells_actor->GetProperty()->SetOpacity(0.6);
      cells_actor->VisibilityOff();
      main->AddActor(cells_actor);
      main_render_started->SetClientData(this);
      main_render_started->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
        static_cast<Viewer::Impl*>(self)->on_main_render();
      });
      main->AddObserver(vtkCommand::StartEvent, main_render_started);
      const int depth = top;
      const bool octree = structure == LodStructure::kOctree;
      level_legend->SetLookupTable(octree ? level_colors.Get() : dag_colors.Get());
      level_legend->SetTitle(octree ? "level" : "DAG level");
      level_legend->SetNumberOfLabels(std::min(depth + 1, 10));
      level_legend->SetLabelFormat("%.0f");
      level_legend->SetMaximumWidthInPixels(90);
      level_legend->UnconstrainedFontSizeOn();
      for (vtkTextProperty* tp : {level_legend->GetTitleTextProperty(), level_legend->GetLabelTextProperty()}) {
        tp->SetColor(0.1, 0.1, 0.1);
        tp->SetFontSize(13);
        tp->ItalicOff();
        tp->BoldOff();
        tp->ShadowOff();
      }
      level_legend->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
      level_legend->GetPositionCoordinate()->SetValue(0.9, 0.25);
      level_legend->SetWidth(0.08);
      level_legend->SetHeight(0.5);
      level_legend->VisibilityOff();
      main->AddViewProp(level_legend);
      help->SetInput(octree ? "slider / Left Right (1 %) / Up Down (10 %): level   t slider by % or triangles\n"
                              "1 shaded  2 wireframe  3 edges  4 points  5 colours\n"
                              "o octree cells   v split view   [ ] its level\n"
                              "r reset camera   s screenshot   q quit"
                            : "slider / Left Right (1 %) / Up Down (10 %): level   t slider by % or triangles\n"
                              "1 shaded  2 wireframe  3 edges  4 points  5 colours\n"
                              "c camera cut   f freeze it   [ ] its pixel error   l colour by DAG level\n"
                              "v split view   [ ] its level (without camera cut)\n"
                              "r reset camera   s screenshot   q quit");

      vtkNew<vtkSliderRepresentation2D> rep;
      rep->GetPoint1Coordinate()->SetCoordinateSystemToNormalizedDisplay();
      rep->GetPoint1Coordinate()->SetValue(0.15, 0.07);
      rep->GetPoint2Coordinate()->SetCoordinateSystemToNormalizedDisplay();
      rep->GetPoint2Coordinate()->SetValue(0.85, 0.07);
      rep->SetSliderLength(0.02);
      rep->SetSliderWidth(0.03);
      rep->SetTubeWidth(0.006);
      rep->SetEndCapLength(0.01);
      rep->SetTitleHeight(0.025);
      rep->SetLabelHeight(0.022);
      rep->GetTitleProperty()->SetColor(0.1, 0.1, 0.1);
      rep->GetLabelProperty()->SetColor(0.1, 0.1, 0.1);
      rep->GetTubeProperty()->SetColor(0.55, 0.55, 0.55);
      rep->GetSliderProperty()->SetColor(0.85, 0.35, 0.1);
      rep->GetCapProperty()->SetColor(0.4, 0.4, 0.4);
      slider = vtkSmartPointer<vtkSliderWidget>::New();
      slider->SetInteractor(interactor);
      slider->SetRepresentation(rep);
      slider->SetDefaultRenderer(main);
      slider->SetCurrentRenderer(main);
      slider->SetAnimationModeToJump();
      slider_moved->SetClientData(this);
      slider_moved->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
        static_cast<Viewer::Impl*>(self)->on_slider();
      });
      slider->AddObserver(vtkCommand::InteractionEvent, slider_moved);
      set_slider_unit(false);
      rep->SetValue(std::clamp(options.percent, 0.0, 100.0));
      slider->EnabledOn();
      // Paged, the first view is the camera's: the full detail of a model
      // read page by page may be far larger than the budget.
      if (!input.paged) show_level(slider_request(std::clamp(options.percent, 0.0, 100.0)));
      state.compare_percent = std::clamp(options.compare_percent, 0.0, 100.0);
    }
  }
  reset_camera();
  if (input.paged) set_camera_cut(true);
  update_overlay();
}

void Viewer::Impl::set_slider_unit(bool by_triangles) {
  if (!slider) return;
  auto* rep = static_cast<vtkSliderRepresentation2D*>(slider->GetRepresentation());
  state.slider_by_triangles = by_triangles;
  if (by_triangles) {
    const std::int64_t lo = source->min_triangles();
    rep->SetMinimumValue(double(lo));
    rep->SetMaximumValue(double(std::max<std::int64_t>(source->max_triangles(), lo + 1)));
    rep->SetValue(double(state.triangles));
    rep->SetLabelFormat("%.0f");
    rep->SetTitleText("triangles (finest level within)");
  } else {
    rep->SetMinimumValue(0);
    rep->SetMaximumValue(100);
    rep->SetValue(state.percent);
    rep->SetLabelFormat("%.1f");
    rep->SetTitleText(state.structure == LodStructure::kOctree ? "LOD % (share of the LOD array)"
                                                                : "LOD % (share of the full-detail triangles)");
  }
  state.slider_value = rep->GetValue();
}

LevelRequest Viewer::Impl::slider_request(double v) const {
  LevelRequest r = state.slider_by_triangles ? LevelRequest::at_triangles(std::int64_t(std::llround(v)))
                                             : LevelRequest::at_percent(std::clamp(v, 0.0, 100.0));
  // The stored cuts, by reference: a slider asks at every move, and refining
  // to the count takes about 3.5 us a triangle (lod/clusters/cut_refinement.h).
  r.refine = false;
  return r;
}

void Viewer::Impl::on_slider() {
  auto* rep = static_cast<vtkSliderRepresentation2D*>(slider->GetRepresentation());
  const double v = rep->GetValue();
  state.slider_value = v;
  // A slider move takes a uniform level again: the camera cut ends.
  state.camera_cut = false;
  state.frozen = false;
  show_level(slider_request(v));
  update_overlay();
}

void Viewer::Impl::show_level(const LevelRequest& request) {
  const bool uniform = request.kind != LevelRequest::Kind::kCamera;
  const LevelCut& cut = paged_view && !uniform ? paged_view->view(request.camera) : source->cut(request);
  if (paged_view && !uniform) state.cut_pixel_error = paged_view->pixel_error();
  // The same level again (a slider move inside one step): nothing to send.
  const bool same = uniform && shown_uniform && state.triangles == cut.triangles.size() && state.triangles != 0 &&
                    (state.structure == LodStructure::kOctree
                         ? cut.priority == state.priority
                         : cut.error == state.error && cut.clusters == state.clusters);
  shown_uniform = uniform;
  if (same) return;
  show_cut(cut);
}

void Viewer::Impl::show_cut(const LevelCut& cut) {
  // Only the triangles change: they index the model's vertex array, which
  // went to VTK (and the GPU) once.
  const std::vector<Triangle>& triangles = cut.triangles;
  const auto start = Clock::now();
  // Paged, the cut's vertices come with it (compact_level from its pages).
  TriangleMesh paged_mesh;
  if (paged_view) {
    paged_mesh = compact_level(*input.model, triangles);
    level_poly = mesh_to_poly_data(paged_mesh);
    mesh_mapper->SetInputData(level_poly);
  } else {
    set_triangles(level_poly, triangles);
  }
  if (state.structure == LodStructure::kClusters) {
    // Each triangle's DAG level as cell data, always in step with the cells.
    std::vector<std::uint8_t> levels = paged_view && state.camera_cut && !shown_uniform
                                           ? paged_view->extractor().triangle_levels()
                                           : source->triangle_levels();
    levels.resize(triangles.size(), 0);
    auto array = vtkSmartPointer<vtkUnsignedCharArray>::New();
    array->SetName("DagLevel");
    array->SetNumberOfTuples(vtkIdType(levels.size()));
    if (!levels.empty()) std::memcpy(array->GetPointer(0), levels.data(), levels.size());
    level_poly->GetCellData()->AddArray(array);
  }
  // Vertices the level uses, as compact_level would keep them.
  std::size_t used = paged_mesh.positions.size();
  if (!paged_view) {
    for (const Triangle& t : triangles)
      for (std::int32_t v : t)
        if (!vertex_used[std::size_t(v)]) vertex_used[std::size_t(v)] = 1, ++used;
    for (const Triangle& t : triangles)
      for (std::int32_t v : t) vertex_used[std::size_t(v)] = 0;
  }
  level_vertices = used;
  // How long edges are on screen (a sample of them is enough): dense
  // wireframes are drawn lit and grey instead of black (style_wireframe).
  const std::size_t stride = std::max<std::size_t>(1, triangles.size() / 4096);
  const double diagonal = box.diagonal();
  const double mean_edge = paged_view ? mean_edge_length(paged_mesh.positions, paged_mesh.triangles, stride)
                                     : mean_edge_length(input.model->vertices.positions, triangles, stride);
  edge_pixels = diagonal > 0 ? mean_edge / diagonal * options.height : 8;
  if (state.mode == DrawMode::wireframe) apply_mode();
  state.convert_ms = ms_since(start);
  state.extract_ms = cut.extract_seconds * 1e3;
  state.priority = cut.priority;
  state.percent = cut.percent;
  state.error = cut.error;
  state.clusters = cut.clusters;
  state.triangles = triangles.size();
  rendering_after_change = true;
  if (state.cells) update_cells();
}

CameraView Viewer::Impl::camera_view() const {
  double p[3], f[3], u[3];
  camera->GetPosition(p);
  camera->GetFocalPoint(f);
  camera->GetViewUp(u);
  CameraView v;
  v.eye = Vec3f(float(p[0]), float(p[1]), float(p[2]));
  v.target = Vec3f(float(f[0]), float(f[1]), float(f[2]));
  v.up = Vec3f(float(u[0]), float(u[1]), float(u[2]));
  v.fov_degrees = float(camera->GetViewAngle());
  const int* size = window->GetSize();
  v.height = size && size[1] > 0 ? size[1] : options.height;
  return v;
}

void Viewer::Impl::select_for_camera(const CameraView& view) {
  before_last_view = last_view;
  have_before = have_view;
  last_view = view;
  have_view = true;
  show_level(LevelRequest::for_camera(view, state.pixel_error));
  ++state.camera_selections;
  if (paged_view && have_before) {
    // The camera keeps moving as it moved: read what that view will need.
    CameraView next = view;
    next.eye = view.eye + (view.eye - before_last_view.eye);
    next.target = view.target + (view.target - before_last_view.target);
    if ((next.eye - next.target).norm() > 0) state.pages_prefetched += paged_view->prefetch(next);
  }
  update_overlay();
}

// The main renderer starts drawing: a live camera cut follows a camera that
// moved since its last selection (any change of eye, target, up, angle or
// window height; the clipping range the renderer resets does not count).
void Viewer::Impl::on_main_render() {
  if (!state.camera_cut || state.frozen) return;
  const CameraView v = camera_view();
  if (have_view && v.eye == last_view.eye && v.target == last_view.target && v.up == last_view.up &&
      v.fov_degrees == last_view.fov_degrees && v.height == last_view.height)
    return;
  select_for_camera(v);
  render_start = Clock::now();  // the window's StartEvent came before the change
}

void Viewer::Impl::set_camera_cut(bool on) {
  state.camera_cut = on;
  state.frozen = false;
  if (on) select_for_camera(camera_view());
  else show_level(slider_request(state.slider_value));
}

void Viewer::Impl::show_compare() {
  const Level level = compare_source->at_percent(state.compare_percent);
  compare_mapper->SetInputData(mesh_to_poly_data(level.mesh));
  state.compare_triangles = level.mesh.triangles.size();
  char text[200];
  if (level.structure == LodStructure::kOctree)
    std::snprintf(text, sizeof text, "LOD %.1f %% (priority %zu)\n%s triangles\n%s vertices", level.percent,
                  level.priority, thousands(level.mesh.triangles.size()).c_str(),
                  thousands(level.mesh.positions.size()).c_str());
  else
    std::snprintf(text, sizeof text, "LOD %.1f %% (error %.3g, %zu clusters)\n%s triangles\n%s vertices",
                  level.percent, level.error, level.clusters, thousands(level.mesh.triangles.size()).c_str(),
                  thousands(level.mesh.positions.size()).c_str());
  compare_overlay->SetInput(text);
}

void Viewer::Impl::update_cells() {
  const std::vector<std::int32_t> cut = lod_cut(*input.model, state.priority);
  cells_mapper->SetInputData(cell_outlines(*input.model, cut));
  state.cell_count = cut.size();
}

void Viewer::Impl::apply_mode() {
  vtkProperty* p = mesh_actor->GetProperty();
  style_shaded(p);
  p->SetPointSize(3);
  p->SetEdgeColor(0.15, 0.15, 0.15);
  mesh_mapper->ScalarVisibilityOff();
  compare_mapper->ScalarVisibilityOff();
  switch (state.mode) {
    case DrawMode::shaded: break;
    case DrawMode::wireframe: style_wireframe(p, edge_pixels); break;
    case DrawMode::shaded_edges: p->EdgeVisibilityOn(); break;
    case DrawMode::points: p->SetRepresentationToPoints(); break;
    case DrawMode::vertex_colors:
      for (vtkPolyDataMapper* m : {mesh_mapper.Get(), compare_mapper.Get()}) {
        m->ScalarVisibilityOn();
        m->SetScalarModeToUsePointFieldData();
        m->SelectColorArray("Colors");
        m->SetColorModeToDirectScalars();
      }
      break;
  }
  if (state.dag_colors) {  // over any mode's colours
    mesh_mapper->ScalarVisibilityOn();
    mesh_mapper->SetScalarModeToUseCellFieldData();
    mesh_mapper->SelectColorArray("DagLevel");
    mesh_mapper->SetColorModeToMapScalars();
    mesh_mapper->SetLookupTable(dag_colors);
    mesh_mapper->UseLookupTableScalarRangeOn();
  }
}

void Viewer::Impl::update_overlay() {
  vtkPolyData* poly = mesh_mapper->GetInput();
  if (input.kind != ViewerInput::Kind::scans) {
    state.triangles = poly ? std::size_t(poly->GetNumberOfPolys()) : 0;
    state.vertices = state.has_levels ? level_vertices : poly ? std::size_t(poly->GetNumberOfPoints()) : 0;
  }
  if (paged_view) {
    const PageStats& read = paged_view->pages().stats();
    state.page_bytes = read.resident_bytes;
    state.peak_page_bytes = read.peak_resident_bytes;
    state.pages_read = read.pages_read;
  }
  std::ostringstream text;
  char line[256];
  if (input.kind == ViewerInput::Kind::scans) {
    std::snprintf(line, sizeof line, "%zu scans, %s oriented points\nnormals %s", input.scans.size(),
                  thousands(state.vertices).c_str(), state.normals ? "shown (n hides)" : "hidden (n shows)");
    text << line;
  } else if (!state.has_levels) {
    std::snprintf(line, sizeof line, "%s\n%s triangles\n%s vertices\n%s", input.source.c_str(),
                  thousands(state.triangles).c_str(), thousands(state.vertices).c_str(), draw_mode_name(state.mode));
    text << line;
  } else {
    if (state.structure == LodStructure::kOctree)
      std::snprintf(line, sizeof line, "octree: LOD %.1f %%   priority %zu", state.percent, state.priority);
    else if (state.camera_cut)
      std::snprintf(line, sizeof line, "clusters: LOD %.1f %%   camera cut at %g px%s   %s clusters", state.percent,
                    state.pixel_error, state.frozen ? " (frozen)" : "", thousands(state.clusters).c_str());
    else
      std::snprintf(line, sizeof line, "clusters: LOD %.1f %%   error %.3g   %s clusters", state.percent, state.error,
                    thousands(state.clusters).c_str());
    text << line;
    std::snprintf(line, sizeof line, "\n%s triangles\n%s vertices\nextract %.1f ms (+%.1f ms to VTK)\n%s",
                  thousands(state.triangles).c_str(), thousands(state.vertices).c_str(), state.extract_ms,
                  state.convert_ms, draw_mode_name(state.mode));
    text << line;
    if (state.cells) text << "\noctree cells: " << thousands(state.cell_count) << " nodes of the cut";
    if (state.structure == LodStructure::kClusters) {
      if (state.camera_cut)
        text << "\ncamera cut " << (state.frozen ? "frozen (f follows the camera again)" : "live (f freezes it)")
             << ", [ ] pixel error, c off";
      else
        text << "\nuniform cut (c: camera cut)";
      if (state.dag_colors) text << "\ncolour: DAG level (" << state.levels << " levels, red finest, blue coarsest)";
    }
    if (state.paged) {
      std::snprintf(line, sizeof line, "\npages held %.1f of %.0f MiB, %s read", double(state.page_bytes) / 1048576,
                    double(state.page_budget) / 1048576, thousands(state.pages_read).c_str());
      text << line;
      if (state.camera_cut && state.cut_pixel_error > state.pixel_error)
        text << "; cut at " << state.cut_pixel_error << " px to fit";
    }
  }
  state.overlay = text.str();
  overlay->SetInput(state.overlay.c_str());
}

void Viewer::Impl::reset_camera() {
  frame_camera(camera, box, 0, 0, state.split ? 0.5 * options.width / options.height
                                              : double(options.width) / options.height);
  main->ResetCameraClippingRange();
  if (state.split) compare->ResetCameraClippingRange();
}

void Viewer::Impl::set_split(bool on) {
  if (!state.has_levels || on == state.split) return;
  state.split = on;
  // The slider stays under the left half's level.
  auto* rep = static_cast<vtkSliderRepresentation2D*>(slider->GetRepresentation());
  const double width = on ? 0.5 : 1.0;
  rep->GetPoint1Coordinate()->SetValue(0.15 * width, 0.07);
  rep->GetPoint2Coordinate()->SetValue(0.85 * width, 0.07);
  rep->Modified();
  rep->BuildRepresentation();
  if (on) {
    main->SetViewport(0, 0, 0.5, 1);
    compare->SetViewport(0.5, 0, 1, 1);
    window->AddRenderer(compare);
    show_compare();
  } else {
    window->RemoveRenderer(compare);
    main->SetViewport(0, 0, 1, 1);
  }
}

bool Viewer::Impl::key(const std::string& k) {
  const bool mesh = input.kind != ViewerInput::Kind::scans;
  const bool clusters = state.has_levels && state.structure == LodStructure::kClusters;
  auto mode = [&](DrawMode m) {
    if (!mesh) return;
    state.mode = m;
    apply_mode();
  };
  if (k == "1") mode(DrawMode::shaded);
  else if (k == "2" || k == "w") mode(DrawMode::wireframe);
  else if (k == "3") mode(DrawMode::shaded_edges);
  else if (k == "4") mode(DrawMode::points);
  else if (k == "5") mode(DrawMode::vertex_colors);
  else if (k == "r") reset_camera();
  else if (k == "s") save("");
  else if (k == "n" && !mesh) {
    state.normals = !state.normals;
    for (auto& a : normal_actors) a->SetVisibility(state.normals);
  } else if (k == "c" && clusters) {
    set_camera_cut(!state.camera_cut);
  } else if (k == "f" && clusters && state.camera_cut) {
    state.frozen = !state.frozen;
    if (!state.frozen) select_for_camera(camera_view());  // catch up with the camera
  } else if ((k == "bracketleft" || k == "[" || k == "bracketright" || k == "]") && state.camera_cut) {
    const bool finer = k == "bracketleft" || k == "[";
    state.pixel_error = std::clamp(state.pixel_error * (finer ? 0.5 : 2.0), 1.0 / 64, 1024.0);
    // A frozen cut is chosen again for the camera it was frozen at.
    select_for_camera(state.frozen ? last_view : camera_view());
  } else if (k == "l" && clusters) {
    state.dag_colors = !state.dag_colors;
    apply_mode();
    level_legend->SetVisibility(state.dag_colors);
  } else if (k == "o" && state.has_levels && state.structure == LodStructure::kOctree) {
    state.cells = !state.cells;
    if (state.cells) update_cells();
    cells_actor->SetVisibility(state.cells);
    level_legend->SetVisibility(state.cells);
  } else if (k == "v" && state.has_levels) {
    set_split(!state.split);
    reset_camera();
  } else if ((k == "bracketleft" || k == "[" || k == "bracketright" || k == "]") && state.has_levels) {
    const double step = (k == "bracketleft" || k == "[") ? -10 : 10;
    state.compare_percent = std::clamp(state.compare_percent + step, 0.0, 100.0);
    if (state.split) show_compare();
  } else if (k == "t" && state.has_levels) {
    set_slider_unit(!state.slider_by_triangles);
  } else if ((k == "Left" || k == "Right" || k == "Up" || k == "Down") && state.has_levels) {
    auto* rep = static_cast<vtkSliderRepresentation2D*>(slider->GetRepresentation());
    const double range = rep->GetMaximumValue() - rep->GetMinimumValue();
    const double step = (k == "Left" || k == "Right" ? 0.01 : 0.1) * range * (k == "Left" || k == "Down" ? -1 : 1);
    rep->SetValue(std::clamp(rep->GetValue() + step, rep->GetMinimumValue(), rep->GetMaximumValue()));
    slider->InvokeEvent(vtkCommand::InteractionEvent);
  } else {
    return false;
  }
  update_overlay();
  if (interactor->GetInitialized() || options.offscreen) render();
  return true;
}

std::string Viewer::Impl::next_screenshot_path() const {
  namespace fs = std::filesystem;
  const fs::path first(options.screenshot);
  if (!fs::exists(first)) return first.string();
  for (int n = 2;; ++n) {
    fs::path p = first.parent_path() / (first.stem().string() + "_" + std::to_string(n) + first.extension().string());
    if (!fs::exists(p)) return p.string();
  }
}

std::string Viewer::Impl::save(const std::string& path) {
  const std::string target = path.empty() ? next_screenshot_path() : path;
  check_png_output(target);
  // Neither the help nor the slider's handle belong in the picture's corner.
  help->VisibilityOff();
  write_window_png(window, target);
  help->VisibilityOn();
  state.last_screenshot = target;
  return target;
}

Viewer::Viewer(ViewerInput input, const ViewerOptions& options)
    : impl_(std::make_unique<Impl>(std::move(input), options)) {
  require_display("view");
  impl_->build();
  impl_->interactor->Initialize();
  impl_->render();
}

Viewer::~Viewer() {
  if (impl_ && impl_->slider) impl_->slider->EnabledOff();
}

vtkRenderWindowInteractor* Viewer::interactor() const { return impl_->interactor; }
vtkSliderWidget* Viewer::slider() const { return impl_->slider; }

ViewerState Viewer::state() const { return impl_->state; }

void Viewer::move_slider(double value) {
  if (!impl_->slider) throw InputError(impl_->input.source, "the slider needs a LOD model (.mco); this is not one");
  auto* rep = static_cast<vtkSliderRepresentation2D*>(impl_->slider->GetRepresentation());
  rep->SetValue(value);
  impl_->slider->InvokeEvent(vtkCommand::InteractionEvent);
  impl_->slider->InvokeEvent(vtkCommand::EndInteractionEvent);
  impl_->render();
}

void Viewer::set_slider_by_triangles(bool by_triangles) {
  if (!impl_->slider) throw InputError(impl_->input.source, "the slider needs a LOD model (.mco); this is not one");
  impl_->set_slider_unit(by_triangles);
  impl_->update_overlay();
}

void Viewer::press_key(const std::string& keysym) {
  vtkRenderWindowInteractor* i = impl_->interactor;
  const char code = keysym.size() == 1 ? keysym[0] : keysym == "bracketleft" ? '[' : keysym == "bracketright" ? ']' : 0;
  i->SetKeyEventInformation(0, 0, code, 1, keysym.c_str());
  i->InvokeEvent(vtkCommand::KeyPressEvent);
  i->InvokeEvent(vtkCommand::CharEvent);
  i->InvokeEvent(vtkCommand::KeyReleaseEvent);
  impl_->render();
}

std::string Viewer::screenshot(const std::string& path) { return impl_->save(path); }

void Viewer::run_script(std::istream& in, const std::string& source, std::ostream& log) {
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::string command, arg;
    words >> command;
    if (command.empty() || command[0] == '#') continue;
    std::getline(words >> std::ws, arg);
    const auto where = "line " + std::to_string(number) + ": ";
    auto number_arg = [&] {
      char* end = nullptr;
      const double v = std::strtod(arg.c_str(), &end);
      if (arg.empty() || *end != '\0' || !std::isfinite(v))
        throw InputError(source, where + "'" + command + "' needs a number, got '" + arg + "'");
      return v;
    };
    if (command == "percent" || command == "triangles" || command == "slider") {
      const double v = number_arg();
      if (command != "slider") set_slider_by_triangles(command == "triangles");
      move_slider(v);
    } else if (command == "key") {
      if (arg.empty()) throw InputError(source, where + "'key' needs a key name (o, s, Right, ...)");
      press_key(arg);
    } else if (command == "orbit" || command == "zoom") {
      const double v = number_arg();
      if (command == "zoom" && !(v > 0))
        throw InputError(source, where + "'zoom' needs a factor above 0 (2 goes twice as close), got '" + arg + "'");
      if (command == "orbit") move_camera(v, 1);
      else move_camera(0, v);
    } else if (command == "screenshot") {
      screenshot(arg);
    } else if (command != "print") {
      throw InputError(source, where + "unknown command '" + command +
                                   "', expected percent, triangles, slider, key, orbit, zoom, screenshot or print");
    }
    log << describe(state()) << (command == "screenshot" ? " -> " + impl_->state.last_screenshot : "") << '\n';
  }
}

void Viewer::move_camera(double azimuth, double dolly) {
  vtkCamera* c = impl_->camera;
  if (azimuth != 0) c->Azimuth(azimuth);
  if (dolly != 1) c->Dolly(dolly);
  c->OrthogonalizeViewUp();
  impl_->main->ResetCameraClippingRange();
  if (impl_->state.split) impl_->compare->ResetCameraClippingRange();
  impl_->render();
}

void Viewer::start() {
  impl_->render();
  impl_->interactor->Start();
}

}  // namespace scan2lod
