// Pictures out: the checks before work and the atomic PNG write after it.
#pragma once

#include <string>

class vtkRenderWindow;

namespace scan2lod {

// Throws InputError unless a PNG could be written at `path`: extension .png
// (any case) in an existing folder. Commands call it before long work.
void check_png_output(const std::string& path);

// Throws InputError with a hint (run under `xvfb-run -a`) when there is no X
// display: Debian's VTK renders through GLX only and would abort the process
// ("bad X server connection") instead of failing.
void require_display(const std::string& what);

// Renders `window` and writes its pixels (RGB) to `path` as a PNG through
// write_atomically. Throws InputError
// naming the file when the write fails.
void write_window_png(vtkRenderWindow* window, const std::string& path);

}  // namespace scan2lod
