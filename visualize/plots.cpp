#include <scan2lod/visualize/plots.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/visualize/levels.h>
#include <scan2lod/visualize/octree_cells.h>
#include <scan2lod/visualize/png_output.h>

#include <vtkAxis.h>
#include <vtkChartMatrix.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#include <vtkVector.h>

#include <algorithm>

namespace scan2lod {
namespace {

vtkSmartPointer<vtkDoubleArray> column(const char* name, const std::vector<double>& values) {
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfTuples(vtkIdType(values.size()));
  std::copy(values.begin(), values.end(), a->GetPointer(0));
  return a;
}

void add_line(vtkChartXY* chart, vtkTable* table, int y_column, const std::uint8_t rgb[3], float width,
              bool points = false) {
  vtkPlot* line = chart->AddPlot(points ? vtkChart::POINTS : vtkChart::LINE);
  line->SetInputData(table, 0, y_column);
  line->SetColor(rgb[0], rgb[1], rgb[2], 255);
  line->SetWidth(width);
}

void label(vtkChartXY* chart, const std::string& title, const char* x, const char* y) {
  chart->SetTitle(title);
  chart->GetTitleProperties()->SetFontSize(15);
  chart->GetTitleProperties()->BoldOn();
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle(x);
  chart->GetAxis(vtkAxis::LEFT)->SetTitle(y);
  for (int a : {vtkAxis::BOTTOM, vtkAxis::LEFT}) {
    chart->GetAxis(a)->GetTitleProperties()->SetFontSize(13);
    chart->GetAxis(a)->GetLabelProperties()->SetFontSize(11);
  }
}

// Fixes the left axis a little beyond the data, so a run of values on the
// range's edge (a metric of 0 for many priorities) is not hidden under the axis.
void pad_left_axis(vtkChartXY* chart, const std::vector<double>& values) {
  if (values.empty()) return;
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  const double margin = 0.05 * std::max(*hi - *lo, 1e-12);
  vtkAxis* axis = chart->GetAxis(vtkAxis::LEFT);
  axis->SetBehavior(vtkAxis::FIXED);
  axis->SetRange(*lo - margin, *hi + margin);
}

}  // namespace

std::vector<LevelError> level_errors(const LodModel& model, LodStructure structure, const TriangleMesh& reference,
                                     const std::vector<double>& percents, std::size_t samples) {
  std::vector<LevelError> out;
  LevelSource source(model, structure);
  Progress progress("error", percents.size());
  CompareOptions compare;
  compare.samples = samples;
  for (double percent : percents) {
    const Level level = source.at_percent(percent);
    const SurfaceComparison c = compare_surfaces(level.mesh, reference, compare);
    LevelError e;
    e.percent = percent;
    e.priority = level.priority;
    e.error = level.error;
    e.triangles = level.mesh.triangles.size();
    const double unit = c.diagonal > 0 ? 100.0 / c.diagonal : 0.0;
    e.mean_to_reference = c.a_to_b.mean * unit;
    e.mean_from_reference = c.b_to_a.mean * unit;
    out.push_back(e);
    progress.advance();
  }
  progress.finish();
  return out;
}

PlotPicture write_lod_plots(const LodModel& model, LodStructure structure, const std::vector<LevelError>& errors,
                            const PlotOptions& options, const std::string& path) {
  require_structure(model, structure, "");
  require_display("plot");
  const int columns = errors.empty() ? 3 : 2, rows = errors.empty() ? 1 : 2;
  PlotPicture picture;
  picture.width = columns * options.chart_width;
  picture.height = rows * options.chart_height;
  picture.full_triangles = LevelExtractor(model, structure).full_triangles();

  vtkNew<vtkContextView> view;
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetMultiSamples(0);
  view->GetRenderWindow()->SetSize(picture.width, picture.height);
  view->GetRenderer()->SetBackground(1, 1, 1);
  vtkNew<vtkChartMatrix> matrix;
  matrix->SetSize(vtkVector2i(columns, rows));
  matrix->SetGutter(vtkVector2f(70.f, 70.f));
  matrix->SetBorders(70, 60, 30, 40);
  view->GetScene()->AddItem(matrix);
  // Chart matrix indices count from the bottom-left; pictures from the top.
  auto chart_at = [&](int i, const std::string& title) {
    const int col = i % columns, row = i / columns;
    picture.charts.push_back({title, col * options.chart_width, row * options.chart_height, options.chart_width,
                              options.chart_height});
    auto* chart = vtkChartXY::SafeDownCast(matrix->GetChart(vtkVector2i(col, rows - 1 - row)));
    return chart;
  };

  // The tables stay alive until the picture is written.
  vtkNew<vtkTable> metrics, head, accumulation, cut_table;
  if (structure == LodStructure::kOctree) {
    const OctreeSeries series = octree_series(model);
    const std::vector<double>& metric = series.metric;
    picture.priorities = metric.size();
    std::vector<double> priority;
    for (std::size_t i = 0; i < metric.size(); ++i) priority.push_back(double(i));
    // Fig. 6.6: the metric of the node each priority number expands. The
    // metric spans orders of magnitude (a few coarse nodes carry most of the
    // area), so it goes on a log axis when enough of it is positive; values
    // under 1e-8 of the largest (0, negative, float rounding) are drawn on
    // that floor.
    double largest = 0;
    std::size_t positive = 0;
    for (double m : metric) largest = std::max(largest, m), positive += m > 0;
    const double floor = 1e-8 * largest;
    const bool log_metric = options.log_metric && positive > metric.size() / 2;
    std::vector<double> shown = metric;
    if (log_metric)
      for (double& m : shown) m = std::max(m, floor);
    const char* metric_title = log_metric ? "LOD metric (log)" : "LOD metric";
    metrics->AddColumn(column("priority", priority));
    metrics->AddColumn(column("LOD metric", shown));
    vtkChartXY* a = chart_at(0, "LOD metric (Fig. 6.6)");
    label(a, "LOD metric (Fig. 6.6)", "priority number", metric_title);
    add_line(a, metrics, 1, kPlotBlue, 1.f);
    if (log_metric) a->GetAxis(vtkAxis::LEFT)->SetLogScale(true);
    else pad_left_axis(a, metric);

    // Fig. 6.7: its first priorities, where the order matters most.
    const std::size_t part = std::min(options.part, metric.size());
    head->AddColumn(column("priority", std::vector<double>(priority.begin(), priority.begin() + long(part))));
    head->AddColumn(column("LOD metric", std::vector<double>(metric.begin(), metric.begin() + long(part))));
    const std::string part_title = "LOD metric, first " + std::to_string(part) + " (Fig. 6.7)";
    vtkChartXY* b = chart_at(1, part_title);
    label(b, part_title, "priority number", "LOD metric");
    add_line(b, head, 1, kPlotBlue, 1.5f);
    pad_left_axis(b, std::vector<double>(metric.begin(), metric.begin() + long(part)));

    // Fig. 6.8: triangles after each number of expansions.
    std::vector<double> steps;
    for (std::size_t i = 0; i < series.triangles.size(); ++i) steps.push_back(double(i));
    accumulation->AddColumn(column("priority", steps));
    accumulation->AddColumn(column("triangles", series.triangles));
    vtkChartXY* c = chart_at(2, "Accumulated triangles (Fig. 6.8)");
    label(c, "Accumulated triangles (Fig. 6.8)", "priority number", "triangles");
    add_line(c, accumulation, 1, kPlotBlue, 2.f);
    pad_left_axis(c, series.triangles);
  } else {
    // The uniform cut at 201 shares of the full triangle count, coarsest first.
    std::vector<double> percents;
    for (int i = 0; i <= 200; ++i) percents.push_back(0.5 * i);
    std::vector<double> tris, error, clusters, vertices;
    for (const LevelSummary& l : summarize_levels(model, structure, percents)) {
      if (!tris.empty() && double(l.triangles) == tris.back()) continue;  // the same cut again
      tris.push_back(double(l.triangles));
      error.push_back(l.error);
      clusters.push_back(double(l.clusters));
      vertices.push_back(double(l.vertices));
    }
    std::size_t positive = 0;
    double smallest = 0, largest = 0;
    for (double e : error) {
      positive += e > 0;
      if (e > 0 && (smallest == 0 || e < smallest)) smallest = e;
      largest = std::max(largest, e);
    }
    const bool log_error = options.log_metric && positive > error.size() / 2;
    // The full-detail cut's 0 has no place on a log axis: it is drawn on a
    // floor below the smallest positive threshold.
    std::vector<double> shown = error;
    if (log_error)
      for (double& e : shown) e = std::max(e, 0.5 * smallest);
    cut_table->AddColumn(column("triangles", tris));
    cut_table->AddColumn(column("error", shown));
    cut_table->AddColumn(column("clusters", clusters));
    cut_table->AddColumn(column("vertices", vertices));
    const char* error_title = log_error ? "object-space error (log)" : "object-space error";
    vtkChartXY* a = chart_at(0, "Error threshold against triangles");
    label(a, "Error threshold against triangles", "triangles", error_title);
    add_line(a, cut_table, 1, kPlotBlue, 2.f);
    if (log_error) {
      a->GetAxis(vtkAxis::LEFT)->SetLogScale(true);
      a->GetAxis(vtkAxis::LEFT)->SetBehavior(vtkAxis::FIXED);
      a->GetAxis(vtkAxis::LEFT)->SetRange(0.4 * smallest, 1.25 * largest);
    } else {
      pad_left_axis(a, error);
    }
    vtkChartXY* b = chart_at(1, "Clusters drawn against triangles");
    label(b, "Clusters drawn against triangles", "triangles", "clusters");
    add_line(b, cut_table, 2, kPlotBlue, 2.f);
    pad_left_axis(b, clusters);
    vtkChartXY* c = chart_at(2, "Vertices used against triangles");
    label(c, "Vertices used against triangles", "triangles", "vertices");
    add_line(c, cut_table, 3, kPlotBlue, 2.f);
    pad_left_axis(c, vertices);
  }

  vtkNew<vtkTable> error_table;
  if (!errors.empty()) {
    std::vector<double> tris, to_ref, from_ref;
    for (const LevelError& e : errors) {
      tris.push_back(double(std::max<std::size_t>(e.triangles, 1)));
      to_ref.push_back(e.mean_to_reference);
      from_ref.push_back(e.mean_from_reference);
    }
    error_table->AddColumn(column("triangles", tris));
    error_table->AddColumn(column("mean, level to reference", to_ref));
    error_table->AddColumn(column("mean, reference to level", from_ref));
    vtkChartXY* d = chart_at(3, "Error against triangles");
    label(d, "Error against triangles", "triangles", "mean distance (% of diagonal)");
    d->GetAxis(vtkAxis::BOTTOM)->SetLogScale(true);
    add_line(d, error_table, 1, kPlotBlue, 2.f);
    add_line(d, error_table, 2, kPlotRed, 2.f);
    d->SetShowLegend(true);
  }

  write_window_png(view->GetRenderWindow(), path);
  return picture;
}

}  // namespace scan2lod
