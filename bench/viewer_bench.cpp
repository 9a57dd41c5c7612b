// How fast the viewer follows its slider (issue 4: under 50 ms of extraction
// plus upload per move on the bunny at R = 256). Drives the real Viewer
// off-screen through its slider widget, like `scan2lod view --script`, over
// levels from 100 % down to 1 % and back, and reports per move:
//   extract  the level's triangles (LevelSource::triangles_at: a LodCursor's move)
//   to VTK   the plain mesh copied into vtkPolyData
//   render   the first render after the change: buffer upload plus drawing
//   redraw   the same frame again, nothing changed: drawing alone (best of 2)
// so that upload ~ render - redraw. Needs an X display: run under xvfb-run.
//
//   xvfb-run -a build/bin/scan2lod_bench_viewer MODEL.mco [--size 1200x800] [--passes 3]
#include <scan2lod/visualize/viewer.h>

#include <vtkRenderWindowInteractor.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace {

struct Stats {
  std::vector<double> v;
  double median() {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
  }
  double max() const { return v.empty() ? 0 : *std::max_element(v.begin(), v.end()); }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s MODEL.mco [--size WxH] [--passes N]\n", argv[0]);
    return 2;
  }
  scan2lod::ViewerOptions options;
  options.offscreen = true;
  int passes = 3;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--size")) std::sscanf(argv[i + 1], "%dx%d", &options.width, &options.height);
    if (!std::strcmp(argv[i], "--passes")) passes = std::max(1, std::atoi(argv[i + 1]));
  }
  try {
    scan2lod::Viewer viewer(scan2lod::load_viewer_input({argv[1]}), options);
    const std::vector<double> down = {100, 90, 80, 70, 60, 50, 40, 30, 20, 10, 5, 1};
    std::vector<double> moves;
    for (int p = 0; p < passes; ++p) {
      moves.insert(moves.end(), down.begin(), down.end());
      moves.insert(moves.end(), down.rbegin() + 1, down.rend());
    }
    Stats extract, convert, render, redraw, upload, slider, full_extract, full_slider;
    std::printf("%8s %10s %10s %10s %10s %10s\n", "LOD %", "triangles", "extract", "to VTK", "render", "redraw");
    for (std::size_t i = 0; i < moves.size(); ++i) {
      viewer.move_slider(moves[i] == 100 ? 99.999 : moves[i]);  // every move a change
      viewer.move_slider(moves[i]);
      const scan2lod::ViewerState s = viewer.state();
      double again = 1e300;  // the quicker of two plain redraws: drawing alone
      for (int k = 0; k < 2; ++k) {
        const auto start = std::chrono::steady_clock::now();
        viewer.interactor()->Render();
        again = std::min(again, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      }
      extract.v.push_back(s.extract_ms);
      convert.v.push_back(s.convert_ms);
      render.v.push_back(s.render_ms);
      redraw.v.push_back(again);
      upload.v.push_back(std::max(0.0, s.render_ms - again));
      slider.v.push_back(s.extract_ms + s.convert_ms + std::max(0.0, s.render_ms - again));
      if (moves[i] == 100) {
        full_extract.v.push_back(s.extract_ms);
        full_slider.v.push_back(s.extract_ms + s.convert_ms + std::max(0.0, s.render_ms - again));
      }
      if (i < down.size())
        std::printf("%8g %10zu %8.1f ms %7.1f ms %7.1f ms %7.1f ms\n", moves[i], s.triangles, s.extract_ms,
                    s.convert_ms, s.render_ms, again);
    }
    std::printf("\n%zu moves, %dx%d window: median (max) ms\n", moves.size(), options.width, options.height);
    std::printf("  extract             %6.1f (%6.1f)\n", extract.median(), extract.max());
    std::printf("  to VTK              %6.1f (%6.1f)\n", convert.median(), convert.max());
    std::printf("  upload (render - redraw) %6.1f (%6.1f)\n", upload.median(), upload.max());
    std::printf("  extraction + upload %6.1f (%6.1f); at 100 %%: %6.1f (%6.1f)\n", slider.median(), slider.max(),
                full_slider.median(), full_slider.max());
    std::printf("  render after a move %6.1f (%6.1f), redraw %6.1f (%6.1f) [Mesa llvmpipe: software drawing]\n",
                render.median(), render.max(), redraw.median(), redraw.max());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scan2lod_bench_viewer: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
