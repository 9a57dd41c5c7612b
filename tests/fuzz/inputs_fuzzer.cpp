// libFuzzer target for the input readers: range-grid PLY, .conf, organized PCD
// and the mesh formats (acquisition/, io/mesh_file). Bad input must end in an
// InputError; a crash, hang, huge allocation or any other exception is a finding.
// Built only with clang (tests/fuzz/build.sh inputs), under AddressSanitizer and UBSan.
//
// An input is one selector byte + the file's bytes. The readers take paths, so
// the bytes go to a file in a per-process folder with the extension the
// selector names:
//   0 .ply  read_range_grid_ply           1 .ply  load_oriented_points (dispatch)
//   2 .conf load_oriented_points, next to a valid range grid 'scan.ply'
//   3 .pcd  read_organized_pcd, then load_oriented_points
//   4 .obj  5 .off  6 .stl  7 .vtp        read_mesh (+ load_oriented_points but .vtp)
// INPUTS_FUZZ_VERBOSE=1 prints each InputError (to check seeds and reproducers).
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/acquisition/organized_pcd.h>
#include <scan2lod/acquisition/range_grid_ply.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/io/mesh_file.h>

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

using namespace scan2lod;
namespace fs = std::filesystem;

namespace {

// The same small grid as the tests' kTinyGrid: a .conf must name a real scan.
const char* kScan =
    "ply\nformat ascii 1.0\nobj_info num_cols 3\nobj_info num_rows 2\n"
    "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
    "element range_grid 6\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n2 0 0\n0 1 0\n1 1 0.5\n"
    "1 0\n1 1\n1 2\n1 3\n1 4\n0\n";

const fs::path& folder() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("scan2lod_inputs_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(d);
    std::ofstream(d / "scan.ply", std::ios::binary) << kScan;
    Progress::set_quiet(true);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(folder(), ec);
    });
    return d;
  }();
  return dir;
}

std::string put(const char* ext, const std::uint8_t* data, std::size_t size) {
  const fs::path p = folder() / (std::string("input") + ext);
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  return p.string();
}

OrientedPoints load(const std::string& path) {
  AcquisitionOptions options;
  options.threads = 1;
  return load_oriented_points({path}, options);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExt[] = {".ply", ".ply", ".conf", ".pcd", ".obj", ".off", ".stl", ".vtp"};
  const int kind = data[0] % 8;
  const std::string path = put(kExt[kind], data + 1, size - 1);
  try {
    switch (kind) {
      case 0: read_range_grid_ply(path); break;
      case 1: load(path); break;
      case 2: load(path); break;
      case 3: {
        ScanPose pose;
        read_organized_pcd(path, &pose);
        load(path);
        break;
      }
      case 7: read_mesh(path); break;
      default: {
        read_mesh(path);
        load(path);
        break;
      }
    }
  } catch (const InputError& e) {
    static const bool verbose = std::getenv("INPUTS_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "inputs_fuzzer: InputError: %s\n", e.what());
  } catch (const std::exception& e) {
    // Readers promise InputError for bad files; anything else is a finding.
    std::fprintf(stderr, "inputs_fuzzer: %s escaped as a non-InputError: %s\n", kExt[kind], e.what());
    std::abort();
  }
  return 0;
}
