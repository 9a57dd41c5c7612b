#include <scan2lod/visualize/png_output.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>
#include <scan2lod/io/file_extension.h>

#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkRenderWindow.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>

namespace scan2lod {

void check_png_output(const std::string& path) {
  const std::filesystem::path p(path);
  const std::string ext = lower_extension(path);
  if (ext != ".png") throw InputError(path, "output must be a .png picture, got extension '" + ext + "'");
  const std::filesystem::path folder = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
  if (!std::filesystem::is_directory(folder))
    throw InputError(path, "folder '" + folder.string() + "' does not exist");
}

void require_display(const std::string& what) {
  const char* display = std::getenv("DISPLAY");
  if (!display || !*display)
    throw InputError("", what + " needs an X display for OpenGL and DISPLAY is not set; on a machine without one, "
                            "run it under `xvfb-run -a scan2lod ...`");
}

void write_window_png(vtkRenderWindow* window, const std::string& path) {
  window->Render();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  write_atomically(path, [&](const std::string& tmp) {
    vtkNew<vtkPNGWriter> writer;
    writer->SetFileName(tmp.c_str());
    writer->SetInputConnection(grab->GetOutputPort());
    writer->Write();
    if (writer->GetErrorCode() != 0 || !std::filesystem::exists(tmp) || std::filesystem::file_size(tmp) == 0)
      throw InputError(path, "could not write the PNG");
  });
}

}  // namespace scan2lod
