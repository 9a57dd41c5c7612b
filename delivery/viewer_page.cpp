#include <scan2lod/delivery/viewer_page.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/atomic_file.h>

#include <cstdio>
#include <filesystem>
#include <string_view>
#include <system_error>

// delivery/CMakeLists.txt defines the two paths when the build has the page:
// the bundle esbuild wrote and the page's HTML. The assembler's .incbin copies
// each file's bytes into this object's read-only data, between two symbols.
#if defined(SCAN2LOD_VIEWER_SCRIPT) && defined(SCAN2LOD_VIEWER_HTML)
#define SCAN2LOD_HAS_VIEWER_PAGE 1
asm(".pushsection .rodata\n"
    ".balign 16\n"
    ".global scan2lod_viewer_script_begin\n"
    "scan2lod_viewer_script_begin:\n"
    ".incbin \"" SCAN2LOD_VIEWER_SCRIPT "\"\n"
    ".global scan2lod_viewer_script_end\n"
    "scan2lod_viewer_script_end:\n"
    ".balign 16\n"
    ".global scan2lod_viewer_html_begin\n"
    "scan2lod_viewer_html_begin:\n"
    ".incbin \"" SCAN2LOD_VIEWER_HTML "\"\n"
    ".global scan2lod_viewer_html_end\n"
    "scan2lod_viewer_html_end:\n"
    ".popsection\n");
extern "C" const char scan2lod_viewer_script_begin[], scan2lod_viewer_script_end[];
extern "C" const char scan2lod_viewer_html_begin[], scan2lod_viewer_html_end[];
#else
#define SCAN2LOD_HAS_VIEWER_PAGE 0
#endif

namespace scan2lod {

#if SCAN2LOD_HAS_VIEWER_PAGE
namespace {

namespace fs = std::filesystem;

std::string_view between(const char* begin, const char* end) { return {begin, std::size_t(end - begin)}; }

void write_page_file(const fs::path& path, std::string_view bytes) {
  write_atomically(path.string(), [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw InputError(path.string(), "cannot be created");
    const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    if (std::fclose(f) != 0 || !written) throw InputError(path.string(), "writing failed (disk full?)");
  });
}

}  // namespace

std::vector<std::string> write_viewer_page(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, "is not a folder; the viewer page goes into a tileset's folder");
  const fs::path folder(dir);
  write_page_file(folder / "index.html", between(scan2lod_viewer_html_begin, scan2lod_viewer_html_end));
  write_page_file(folder / "viewer.js", between(scan2lod_viewer_script_begin, scan2lod_viewer_script_end));
  return {"index.html", "viewer.js"};
}
#else
std::vector<std::string> write_viewer_page(const std::string&) { return {}; }
#endif

}  // namespace scan2lod
