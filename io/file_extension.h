// A file's kind as its name tells it: every reader and writer that picks a
// format by extension asks here, so that "BUN000.PLY" and "bun000.ply" are
// one kind everywhere.
#pragma once

#include <string>

namespace scan2lod {

// The extension of `path`'s file name, with its dot, in lower case (".ply");
// "" when it has none. As std::filesystem::path::extension: the last dot's,
// and none for a name that only starts with a dot (".ply").
std::string lower_extension(const std::string& path);

}  // namespace scan2lod
