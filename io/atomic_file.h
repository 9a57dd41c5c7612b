// Outputs appear under their name complete or not at all. The file is written
// as an anonymous file in the target's folder (O_TMPFILE) and linked into place
// once complete, so that nothing is left when the write fails or the process is
// killed, even by SIGKILL. Where the file system has no anonymous files, a
// hidden temporary name beside the target is used instead, and SIGINT, SIGTERM
// and SIGHUP remove it before the process ends (SIGKILL cannot be caught).
//
// A replaced file keeps its mode (and, where the writer may set it, its owner
// and group); a symbolic link is written through, replacing the file at the
// end of its chain, not the link; a file the user may not write is refused
// ("Permission denied"), as Open3D, PCL and MeshLab refuse it.
#pragma once

#include <functional>
#include <string>

namespace scan2lod {

// Calls write(tmp_path), then puts what it wrote at `path` in one step.
//
// @param[in] path   the output as the user named it; a symbolic link is
//                   followed to the file it finally names, which is replaced.
// @param[in] write  writes the whole file to tmp_path, opening it by that name
//                   (fopen, std::ofstream, VTK, PCL, tinygltf). tmp_path is
//                   /proc/self/fd/N for an anonymous file, or a hidden
//                   `.tmp-PID-NAME` beside the target; it carries no
//                   extension, so a writer picks its format from `path`.
//                   It must not keep tmp_path open after it returns.
//
// Throws InputError naming `path` when check_output_path refuses it, when the
// writer wrote nothing, or when the file cannot be put into place (with the
// system's reason). If write throws, nothing is left and the exception
// propagates. The environment variable SCAN2LOD_TEMP_FILES=named forces the
// hidden-name scheme (for file systems whose anonymous files misbehave).
void write_atomically(const std::string& path,
                      const std::function<void(const std::string& tmp_path)>& write);

// Throws InputError unless a file can be written at `path` (after following
// symbolic links): its folder exists and is writable, and a file already
// there is a regular file (not a folder, device or pipe), writable by this
// user and replaceable (a sticky folder such as /tmp lets only the file's
// owner replace it).
void check_output_path(const std::string& path);

// Throws InputError unless `folder` can hold new files: it is a writable
// folder, or the nearest folder above it that exists is writable (so that it
// can be created).
void check_output_folder(const std::string& folder);

}  // namespace scan2lod
