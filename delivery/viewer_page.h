// The web page that goes beside a tileset (delivery/web/): `index.html` and
// `viewer.js`, three.js and 3DTilesRendererJS bundled by esbuild at build
// time into the one script, which this binary carries. Opened from the
// tileset's folder over HTTP (scan2lod serve), the page loads `tileset.json`
// beside it and nothing from anywhere else.
//
// A build configured without npm (SCAN2LOD_WITH_WEB_VIEWER off) carries no
// page; the tileset is the same either way.
#pragma once

#include <string>
#include <vector>

namespace scan2lod {

// Writes the page's files into the folder `dir`, each atomically
// (io/atomic_file.h), replacing any there, and returns their names
// ("index.html", "viewer.js"); returns an empty list and writes nothing when
// the build carries no page. Throws InputError naming the file when `dir` is
// not a folder or a write fails.
std::vector<std::string> write_viewer_page(const std::string& dir);

}  // namespace scan2lod
