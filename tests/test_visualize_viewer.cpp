// The interactive viewer without a human: built in-process on the bunny model
// and driven by the events a user's hands would send (slider widget
// InteractionEvents, key presses through the interactor), then through
// `scan2lod view --script`. After each move the displayed triangle count must
// be that of the level the extraction API gives for the slider's value.
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/visualize/levels.h>
#include <scan2lod/visualize/octree_cells.h>
#include <scan2lod/visualize/scene.h>
#include <scan2lod/visualize/viewer.h>

#include "test_support.h"

#include <gtest/gtest.h>

#include <vtkCamera.h>
#include <vtkCommand.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkSliderRepresentation.h>
#include <vtkSliderWidget.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

using scan2lod::testing::CliRun;

fs::path scratch() { return scan2lod::testing::scratch_folder("viewer"); }

using scan2lod::testing::have_display;

const std::string kScans = scan2lod::testing::bunny_scans();

using scan2lod::testing::bunny_model;

// A user's slider drag, as the widget reports it.
void drag_slider(scan2lod::Viewer& viewer, double value) {
  vtkSliderWidget* slider = viewer.slider();
  static_cast<vtkSliderRepresentation*>(slider->GetRepresentation())->SetValue(value);
  slider->InvokeEvent(vtkCommand::StartInteractionEvent);
  slider->InvokeEvent(vtkCommand::InteractionEvent);
  slider->InvokeEvent(vtkCommand::EndInteractionEvent);
  viewer.interactor()->Render();
}

// A user's key press, as X delivers it to the interactor.
void type_key(scan2lod::Viewer& viewer, char key) {
  vtkRenderWindowInteractor* i = viewer.interactor();
  const std::string sym(1, key);
  i->SetKeyEventInformation(0, 0, key, 1, sym.c_str());
  i->InvokeEvent(vtkCommand::KeyPressEvent);
  i->InvokeEvent(vtkCommand::CharEvent);
  i->InvokeEvent(vtkCommand::KeyReleaseEvent);
}

double covered_fraction(const fs::path& png) {
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(png.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3];
  image->GetDimensions(dims);
  const auto* p = static_cast<const unsigned char*>(image->GetScalarPointer());
  const int c = image->GetNumberOfScalarComponents();
  std::size_t hits = 0, n = std::size_t(dims[0]) * dims[1];
  for (std::size_t i = 0; i < n; ++i) hits += p[c * i] < 240 || p[c * i + 1] < 240 || p[c * i + 2] < 240;
  return double(hits) / double(n);
}

}  // namespace

TEST(VisualizeViewer, SliderMovesShowTheLevelTheExtractionApiGives) {
  if (!have_display()) GTEST_SKIP() << "no X display; scripts/build.sh test runs the tests under xvfb-run";
  const scan2lod::LodModel model = scan2lod::load_model(bunny_model().string());
  ASSERT_TRUE(model.octree);
  scan2lod::LevelSource levels(model, scan2lod::LodStructure::kOctree);

  scan2lod::ViewerOptions options;
  options.width = 640;
  options.height = 480;
  options.offscreen = true;
  options.screenshot = (scratch() / "shot.png").string();
  options.structure = scan2lod::LodStructure::kOctree;
  scan2lod::Viewer viewer(scan2lod::load_viewer_input({bunny_model().string()}), options);
  ASSERT_NE(viewer.slider(), nullptr);
  EXPECT_EQ(viewer.state().triangles, levels.at_percent(100).mesh.triangles.size());

  for (double percent : {20.0, 60.0, 5.0, 100.0, 0.0, 37.5}) {
    drag_slider(viewer, percent);
    const scan2lod::Level expected = levels.at_percent(percent);
    const scan2lod::ViewerState s = viewer.state();
    EXPECT_EQ(s.priority, expected.priority) << percent << " %";
    EXPECT_EQ(s.triangles, expected.mesh.triangles.size()) << percent << " %";
    EXPECT_EQ(s.vertices, expected.mesh.positions.size()) << percent << " %";
    EXPECT_NE(s.overlay.find(scan2lod::thousands(s.triangles) + " triangles"), std::string::npos) << s.overlay;
    EXPECT_GE(s.extract_ms, 0.0);
  }
  // Fewer triangles further down the slider.
  drag_slider(viewer, 10);
  const std::size_t at10 = viewer.state().triangles;
  drag_slider(viewer, 90);
  EXPECT_GT(viewer.state().triangles, 2 * at10);

  // Keys: drawing modes, octree cells, split view.
  type_key(viewer, '2');
  EXPECT_EQ(viewer.state().mode, scan2lod::DrawMode::wireframe);
  type_key(viewer, '3');
  EXPECT_EQ(viewer.state().mode, scan2lod::DrawMode::shaded_edges);
  type_key(viewer, '4');
  EXPECT_EQ(viewer.state().mode, scan2lod::DrawMode::points);
  type_key(viewer, '5');
  EXPECT_EQ(viewer.state().mode, scan2lod::DrawMode::vertex_colors);
  type_key(viewer, '1');
  EXPECT_EQ(viewer.state().mode, scan2lod::DrawMode::shaded);
  type_key(viewer, 'o');
  ASSERT_TRUE(viewer.state().cells);
  EXPECT_EQ(viewer.state().cell_count, scan2lod::lod_cut(model, viewer.state().priority).size());
  drag_slider(viewer, 0);  // the coarsest offered level: its few cells
  EXPECT_EQ(viewer.state().priority, scan2lod::monotone_priorities(model.octree->lod).front());
  EXPECT_EQ(viewer.state().cell_count, scan2lod::lod_cut(model, viewer.state().priority).size());
  EXPECT_LE(viewer.state().cell_count, 64u);
  drag_slider(viewer, 100);
  type_key(viewer, 'v');
  ASSERT_TRUE(viewer.state().split);
  EXPECT_EQ(viewer.state().compare_triangles, levels.at_percent(20).mesh.triangles.size());
  type_key(viewer, ']');
  EXPECT_EQ(viewer.state().compare_triangles, levels.at_percent(30).mesh.triangles.size());

  // By triangle count: the finest level within the budget.
  type_key(viewer, 't');
  ASSERT_TRUE(viewer.state().slider_by_triangles);
  const std::int64_t budget = std::int64_t(levels.at_percent(50).mesh.triangles.size());
  drag_slider(viewer, double(budget));
  scan2lod::LevelExtractor octree(model, scan2lod::LodStructure::kOctree);
  EXPECT_EQ(viewer.state().priority, octree.extract(scan2lod::LevelRequest::at_triangles(budget)).priority);
  EXPECT_LE(std::int64_t(viewer.state().triangles), budget);
  EXPECT_GT(std::int64_t(viewer.state().triangles), budget * 9 / 10);

  // r frames the camera again, s saves the window.
  type_key(viewer, 'r');
  type_key(viewer, 's');
  ASSERT_EQ(viewer.state().last_screenshot, options.screenshot);
  ASSERT_TRUE(fs::exists(options.screenshot));
  EXPECT_GT(covered_fraction(options.screenshot), 0.1);
  type_key(viewer, 's');  // the first picture is kept, the next gets a number
  EXPECT_EQ(viewer.state().last_screenshot, (scratch() / "shot_2.png").string());
}

TEST(VisualizeViewer, ScriptDrivesTheCommandAndReportsEachStep) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const CliRun info = scan2lod::testing::run_cli("info " + bunny_model().string(), false);
  ASSERT_EQ(info.status, 0);
  const fs::path script = scratch() / "steps.txt", shot = scratch() / "scripted.png";
  std::ofstream(script) << "# a user's session\npercent 20\nkey o\nkey Right\npercent 100\nkey 2\nscreenshot "
                        << shot.string() << "\n";
  const CliRun r = scan2lod::testing::run_cli(
      "view " + bunny_model().string() + " --structure octree --size 500x400 --script " + script.string(), false);
  ASSERT_EQ(r.status, 0) << r.output;
  std::vector<std::string> lines;
  std::istringstream in(r.output);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 7u) << r.output;  // the start, then one per command
  const scan2lod::LodModel model = scan2lod::load_model(bunny_model().string());
  scan2lod::LevelSource levels(model, scan2lod::LodStructure::kOctree);
  auto shows = [&](const std::string& line, double percent) {
    return line.find("triangles " + std::to_string(levels.at_percent(percent).mesh.triangles.size()) + " ") !=
           std::string::npos;
  };
  EXPECT_TRUE(shows(lines[0], 100)) << lines[0];
  EXPECT_TRUE(shows(lines[1], 20)) << lines[1];
  EXPECT_NE(lines[2].find("cells "), std::string::npos);
  EXPECT_EQ(lines[2].find("cells off"), std::string::npos) << lines[2];
  EXPECT_TRUE(shows(lines[3], 21)) << lines[3];  // Right: one percent finer
  EXPECT_TRUE(shows(lines[4], 100)) << lines[4];
  EXPECT_NE(lines[5].find("mode wireframe"), std::string::npos) << lines[5];
  EXPECT_NE(lines[6].find("-> " + shot.string()), std::string::npos) << lines[6];
  EXPECT_GT(covered_fraction(shot), 0.05);
}

namespace {

// The CameraView the viewer derives from its camera after `r`: the framing on
// the model's box (scene.h) in a window of width x height.
scan2lod::CameraView framed_view(const scan2lod::LodModel& model, int width, int height) {
  vtkNew<vtkCamera> camera;
  scan2lod::frame_camera(camera, scan2lod::model_bounds(model), 0, 0, double(width) / height);
  double p[3], f[3], u[3];
  camera->GetPosition(p);
  camera->GetFocalPoint(f);
  camera->GetViewUp(u);
  scan2lod::CameraView v;
  v.eye = scan2lod::Vec3f(float(p[0]), float(p[1]), float(p[2]));
  v.target = scan2lod::Vec3f(float(f[0]), float(f[1]), float(f[2]));
  v.up = scan2lod::Vec3f(float(u[0]), float(u[1]), float(u[2]));
  v.fov_degrees = float(camera->GetViewAngle());
  v.height = height;
  return v;
}

}  // namespace

TEST(VisualizeViewer, ClusterSliderAndCameraCutShowTheFacesLevels) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const scan2lod::LodModel model = scan2lod::load_model(bunny_model().string());
  ASSERT_TRUE(model.clusters);
  scan2lod::LevelSource levels(model, scan2lod::LodStructure::kClusters);
  scan2lod::LevelExtractor extractor(model, scan2lod::LodStructure::kClusters);

  scan2lod::ViewerOptions options;
  options.width = 640;
  options.height = 480;
  options.offscreen = true;
  options.screenshot = (scratch() / "clusters.png").string();
  scan2lod::Viewer viewer(scan2lod::load_viewer_input({bunny_model().string()}), options);  // default: clusters
  ASSERT_EQ(viewer.state().structure, scan2lod::LodStructure::kClusters);
  for (double percent : {20.0, 60.0, 5.0, 100.0, 37.5}) {
    drag_slider(viewer, percent);
    const scan2lod::Level expected = levels.at_percent(percent);
    const scan2lod::ViewerState s = viewer.state();
    EXPECT_EQ(s.triangles, expected.mesh.triangles.size()) << percent << " %";
    EXPECT_EQ(s.vertices, expected.mesh.positions.size()) << percent << " %";
    EXPECT_EQ(s.clusters, expected.clusters) << percent << " %";
    EXPECT_EQ(s.error, expected.error) << percent << " %";
    EXPECT_NE(s.overlay.find(scan2lod::thousands(s.triangles) + " triangles"), std::string::npos) << s.overlay;
  }
  type_key(viewer, 'o');  // octree cells: not on the cluster hierarchy
  EXPECT_FALSE(viewer.state().cells);

  // c: the cut for the framed camera, as the face chooses it at 1 pixel.
  type_key(viewer, 'r');
  type_key(viewer, 'c');
  ASSERT_TRUE(viewer.state().camera_cut);
  EXPECT_FALSE(viewer.state().frozen);
  EXPECT_EQ(viewer.state().pixel_error, 1.0);
  const scan2lod::CameraView view = framed_view(model, options.width, options.height);
  EXPECT_EQ(viewer.state().triangles,
            extractor.extract(scan2lod::LevelRequest::for_camera(view, 1)).triangles.size());
  EXPECT_NE(viewer.state().overlay.find("camera cut"), std::string::npos) << viewer.state().overlay;
  // ]: double the pixel error, a coarser cut; [ twice: half the first.
  const std::size_t at1 = viewer.state().triangles;
  viewer.press_key("bracketright");
  EXPECT_EQ(viewer.state().pixel_error, 2.0);
  EXPECT_EQ(viewer.state().triangles, extractor.extract(scan2lod::LevelRequest::for_camera(view, 2)).triangles.size());
  EXPECT_LE(viewer.state().triangles, at1);
  viewer.press_key("bracketleft");
  viewer.press_key("bracketleft");
  EXPECT_EQ(viewer.state().pixel_error, 0.5);
  EXPECT_GE(viewer.state().triangles, at1);
  viewer.press_key("bracketright");
  // Every camera change selects again: farther away, fewer triangles.
  const std::size_t selections = viewer.state().camera_selections;
  viewer.move_camera(0, 0.25);
  EXPECT_GT(viewer.state().camera_selections, selections);
  const std::size_t far = viewer.state().triangles;
  EXPECT_LT(far, at1);
  viewer.move_camera(30, 1);  // an orbit alone re-selects too
  EXPECT_EQ(viewer.state().camera_selections, selections + 2);
  // f: frozen, the camera moves and the cut stays.
  type_key(viewer, 'f');
  ASSERT_TRUE(viewer.state().frozen);
  const std::size_t frozen = viewer.state().triangles;
  viewer.move_camera(60, 8);
  EXPECT_EQ(viewer.state().triangles, frozen);
  EXPECT_EQ(viewer.state().camera_selections, selections + 2);
  EXPECT_NE(viewer.state().overlay.find("frozen"), std::string::npos);
  type_key(viewer, 'f');  // following again: close up, more detail
  EXPECT_FALSE(viewer.state().frozen);
  EXPECT_GT(viewer.state().triangles, frozen);

  // l: triangles coloured by DAG level; a coarse uniform cut shows the upper levels.
  type_key(viewer, 'l');
  EXPECT_TRUE(viewer.state().dag_colors);
  EXPECT_NE(viewer.state().overlay.find("DAG level"), std::string::npos) << viewer.state().overlay;
  type_key(viewer, 'r');
  drag_slider(viewer, 5);  // the slider ends the camera cut
  EXPECT_FALSE(viewer.state().camera_cut);
  EXPECT_EQ(viewer.state().triangles, levels.at_percent(5).mesh.triangles.size());
  type_key(viewer, 's');
  ASSERT_TRUE(fs::exists(options.screenshot));
  EXPECT_GT(covered_fraction(options.screenshot), 0.1);
  type_key(viewer, 'l');
  EXPECT_FALSE(viewer.state().dag_colors);
}

TEST(VisualizeViewer, ScriptDrivesTheCameraCut) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const fs::path script = scratch() / "camera.txt", shot = scratch() / "camera.png";
  std::ofstream(script) << "percent 20\nkey c\nzoom 0.3\nkey f\nzoom 4\norbit 45\nkey f\nkey bracketright\nkey l\n"
                           "screenshot " << shot.string() << "\nkey c\n";
  const CliRun r = scan2lod::testing::run_cli(
      "view " + bunny_model().string() + " --structure clusters --size 500x400 --script " + script.string(), false);
  ASSERT_EQ(r.status, 0) << r.output;
  std::vector<std::string> lines;
  std::istringstream in(r.output);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 12u) << r.output;
  auto triangles = [](const std::string& line) {
    const std::size_t at = line.find("triangles ");
    return at == std::string::npos ? -1L : std::stol(line.substr(at + 10));
  };
  EXPECT_NE(lines[0].find("structure clusters camera off"), std::string::npos) << lines[0];
  EXPECT_NE(lines[2].find("camera live pixel-error 1.00"), std::string::npos) << lines[2];
  EXPECT_LT(triangles(lines[3]), triangles(lines[2]));  // farther: coarser
  EXPECT_NE(lines[4].find("camera frozen"), std::string::npos) << lines[4];
  EXPECT_EQ(triangles(lines[5]), triangles(lines[4]));  // frozen: the camera moves, the cut stays
  EXPECT_EQ(triangles(lines[6]), triangles(lines[4]));
  EXPECT_NE(lines[7].find("camera live"), std::string::npos) << lines[7];
  EXPECT_GT(triangles(lines[7]), triangles(lines[4]));  // following again, close up
  EXPECT_NE(lines[8].find("pixel-error 2.00"), std::string::npos) << lines[8];
  EXPECT_NE(lines[9].find("dag-colours on"), std::string::npos) << lines[9];
  EXPECT_NE(lines[10].find("-> " + shot.string()), std::string::npos) << lines[10];
  EXPECT_NE(lines[11].find("camera off"), std::string::npos) << lines[11];
  EXPECT_EQ(triangles(lines[11]), triangles(lines[1]));  // back to the slider's 20 %
  EXPECT_GT(covered_fraction(shot), 0.05);
}

// A model read page by page (view --cache): it starts on the camera cut,
// holds no more page bytes than its cache while the camera orbits and
// dollies, and each cut is the whole model's at the pixel error it took.
TEST(VisualizeViewer, APagedModelIsViewedWithinItsCache) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const std::string path = bunny_model().string();
  const scan2lod::LodModel whole = scan2lod::load_model(path);
  scan2lod::LevelExtractor extractor(whole, scan2lod::LodStructure::kClusters);
  const std::uint64_t cache = 1000000;
  scan2lod::ViewerOptions options;
  options.width = 640;
  options.height = 480;
  options.offscreen = true;
  options.screenshot = (scratch() / "paged.png").string();
  scan2lod::ViewerInput input = scan2lod::load_viewer_input({path}, cache);
  ASSERT_TRUE(input.paged);
  const scan2lod::CameraView framed = framed_view(*input.model, options.width, options.height);
  scan2lod::Viewer viewer(std::move(input), options);
  scan2lod::ViewerState s = viewer.state();
  ASSERT_TRUE(s.paged);
  EXPECT_TRUE(s.camera_cut);
  EXPECT_EQ(s.page_budget, cache);
  EXPECT_GE(s.cut_pixel_error, 1.0);
  const auto whole_cut = [&](const scan2lod::CameraView& v, double pixel_error) {
    return extractor.extract(scan2lod::LevelRequest::for_camera(v, pixel_error)).triangles.size();
  };
  EXPECT_EQ(s.triangles, whole_cut(framed, s.cut_pixel_error));
  EXPECT_NE(s.overlay.find("pages held"), std::string::npos) << s.overlay;
  int coarsened = 0;
  for (int i = 0; i < 10; ++i) {
    viewer.move_camera(36, i < 5 ? 0.8 : 1.25);  // in close, then back out
    s = viewer.state();
    EXPECT_LE(s.page_bytes, cache) << "move " << i;
    EXPECT_GT(s.triangles, 0u);
    coarsened += s.cut_pixel_error > 1.0;
  }
  EXPECT_LE(s.peak_page_bytes, cache);
  EXPECT_GT(coarsened, 0) << "close views need more than 1 MB of pages";
  // (Prefetching is PagedModel's test: this model's six pages in reach are all held.)
  EXPECT_NE(scan2lod::describe(s).find(" prefetched "), std::string::npos);
  type_key(viewer, 's');
  EXPECT_GT(covered_fraction(options.screenshot), 0.05);
  // The command line: --cache reads page by page and says so.
  const fs::path script = scratch() / "paged.txt";
  std::ofstream(script) << "zoom 0.5\norbit 90\n";
  const CliRun r = scan2lod::testing::run_cli("view " + path + " --cache 1000K --size 500x400 --script " + script.string(), false);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("camera live"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("budget 1024000"), std::string::npos) << r.output;
  EXPECT_NE(scan2lod::testing::run_cli("view " + path + " --cache none --script " + script.string()).status, 0);
}

TEST(VisualizeViewer, ScanSetsShowPointsAndNormals) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const fs::path script = scratch() / "scans.txt", shot = scratch() / "scans.png";
  std::ofstream(script) << "key n\nscreenshot " << shot.string() << "\n";
  const CliRun r =
      scan2lod::testing::run_cli("view " + kScans + " --size 400x300 --script " + script.string(), false);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("points 358808 normals on\npoints 358808 normals off\n"), std::string::npos) << r.output;
  EXPECT_GT(covered_fraction(shot), 0.1);
}

TEST(VisualizeViewer, BadInputEndsInAClearError) {
  const fs::path bad_script = scratch() / "bad_script.txt";
  std::ofstream(bad_script) << "percent 20\njump 3\n";
  struct Case {
    std::string args, expected;
  };
  const std::vector<Case> cases = {
      {"view " + (scratch() / "missing.mco").string(), "missing.mco"},
      {"view " + (scratch() / "notes.txt").string(), "view expects a model (.mco), a mesh"},
      {"view " + bunny_model().string() + " --percent 150", "between 0 and 100"},
      {"view " + bunny_model().string() + " --script " + (scratch() / "none.txt").string(), "none.txt"},
      {"view " + bunny_model().string() + " --screenshot shot.jpg", ".png"},
      {"view " + bunny_model().string() + " --structure tree", "--structure"},
      {"view " + kScans + " --structure octree", "--structure applies to a .mco model"},
  };
  for (const Case& c : cases) {
    const CliRun r = scan2lod::testing::run_cli(c.args);
    EXPECT_NE(r.status, 0) << c.args;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << " -> " << r.output;
  }
  if (have_display()) {
    const CliRun r = scan2lod::testing::run_cli("view " + bunny_model().string() + " --script " + bad_script.string());
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("bad_script.txt: line 2: unknown command 'jump'"), std::string::npos) << r.output;
  }
}
