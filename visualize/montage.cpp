#include <scan2lod/visualize/montage.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/mesh_edges.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/visualize/levels.h>
#include <scan2lod/visualize/png_output.h>
#include <scan2lod/visualize/poly_data.h>
#include <scan2lod/visualize/scene.h>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>

#include <cstdio>
#include <cstdlib>

namespace scan2lod {

RenderMode parse_render_mode(const std::string& text) {
  if (text == "shaded") return RenderMode::shaded;
  if (text == "wireframe") return RenderMode::wireframe;
  if (text == "both") return RenderMode::both;
  throw InputError("", "--mode must be shaded, wireframe or both, got '" + text + "'");
}

void parse_size(const std::string& text, const std::string& flag, int* width, int* height) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 1 || h < 1 ||
      w > 8192 || h > 8192)
    throw InputError("", flag + " expects WIDTHxHEIGHT in pixels (1 to 8192, e.g. 400x400), got '" + text + "'");
  *width = w;
  *height = h;
}

Montage render_montage(const LodModel& model, LodStructure structure, const std::vector<double>& percents,
                       const MontageOptions& options, const std::string& path) {
  if (percents.empty()) throw InputError("", "render needs at least one level");
  if (options.panel_width < 16 || options.panel_height < 16)
    throw InputError("", "panels must be at least 16x16 pixels");
  require_structure(model, structure, "");
  require_display("render");

  const bool both = options.mode == RenderMode::both;
  const int columns = both ? 2 : int(percents.size());
  const int rows = both ? int(percents.size()) : 1;
  Montage montage;
  montage.width = columns * options.panel_width;
  montage.height = rows * options.panel_height;

  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);  // the same pixels every run
  window->SetSize(montage.width, montage.height);

  vtkNew<vtkCamera> camera;
  if (options.camera) {
    ViewCamera local = *options.camera;  // into the model's frame
    local.eye -= model.origin;
    local.target -= model.origin;
    place_camera(camera, local, model_bounds(model));
  } else {
    frame_camera(camera, model_bounds(model), options.azimuth, options.elevation,
                 double(options.panel_width) / double(options.panel_height));
  }

  LevelSource source(model, structure);
  Progress progress("render", percents.size());
  for (std::size_t i = 0; i < percents.size(); ++i) {
    const Level level = source.at_percent(percents[i]);
    vtkSmartPointer<vtkPolyData> poly = mesh_to_poly_data(level.mesh);
    char caption[160];
    std::snprintf(caption, sizeof caption, "LOD %g %%   %s triangles   %s vertices", percents[i],
                  thousands(level.mesh.triangles.size()).c_str(), thousands(level.mesh.positions.size()).c_str());
    for (int c = 0; c < (both ? 2 : 1); ++c) {
      MontagePanel panel;
      panel.mode = both ? (c == 0 ? RenderMode::wireframe : RenderMode::shaded) : options.mode;
      const int column = both ? c : int(i), row = both ? int(i) : 0;
      panel.x = column * options.panel_width;
      panel.y = row * options.panel_height;
      panel.width = options.panel_width;
      panel.height = options.panel_height;
      panel.percent = percents[i];
      panel.priority = level.priority;
      panel.error = level.error;
      panel.clusters = level.clusters;
      panel.triangles = level.mesh.triangles.size();
      panel.vertices = level.mesh.positions.size();
      montage.panels.push_back(panel);

      vtkNew<vtkRenderer> renderer;
      renderer->SetViewport(double(column) / columns, 1.0 - double(row + 1) / rows, double(column + 1) / columns,
                            1.0 - double(row) / rows);
      renderer->SetBackground(1, 1, 1);
      renderer->SetActiveCamera(camera);
      vtkNew<vtkPolyDataMapper> mapper;
      mapper->SetInputData(poly);
      mapper->ScalarVisibilityOff();
      vtkNew<vtkActor> actor;
      actor->SetMapper(mapper);
      if (panel.mode == RenderMode::wireframe) {
        const double diagonal = model_bounds(model).diagonal();
        const double edge_pixels =
            diagonal > 0 ? mean_edge_length(level.mesh.positions, level.mesh.triangles) / diagonal * panel.height : 8;
        style_wireframe(actor->GetProperty(), edge_pixels);
        renderer->UseHiddenLineRemovalOn();
      } else {
        style_shaded(actor->GetProperty());
      }
      renderer->AddActor(actor);
      window->AddRenderer(renderer);
      if (!options.captions) continue;
      vtkNew<vtkTextActor> text;
      text->SetInput(caption);
      vtkTextProperty* tp = text->GetTextProperty();
      tp->SetFontSize(std::max(10, options.panel_height / 26));
      tp->SetColor(0.15, 0.15, 0.15);
      tp->SetJustificationToCentered();
      tp->SetVerticalJustificationToBottom();
      text->SetTextScaleModeToNone();
      text->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
      text->GetPositionCoordinate()->SetValue(0.5, 0.02);
      renderer->AddViewProp(text);
    }
    progress.advance();
  }
  progress.finish();
  write_window_png(window, path);
  return montage;
}

}  // namespace scan2lod
