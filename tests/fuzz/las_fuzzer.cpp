// libFuzzer target for the LAS reader (acquisition/las_file.h). Bad input
// must end in an InputError; a crash, hang, huge allocation or any other
// exception is a finding, and so is a cloud that is not what the header
// promised (another point count, colours where the format has none).
// Built only with clang (tests/fuzz/build.sh las), under AddressSanitizer and UBSan.
//
// An input is the file's bytes. The reader takes a path, so they go to a file
// in a per-process folder (in /dev/shm). LAS_FUZZ_VERBOSE=1 prints each InputError.
#include <scan2lod/acquisition/las_file.h>
#include <scan2lod/core/error.h>

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

const fs::path& folder() {
  static const fs::path dir = [] {
    // In memory where there is /dev/shm: ext4 writes a file truncated and
    // rewritten back to disk at close (auto_da_alloc), 3 ms an input.
    std::error_code ec;
    const fs::path base = fs::is_directory("/dev/shm", ec) ? fs::path("/dev/shm") : fs::temp_directory_path();
    fs::path d = base / ("scan2lod_las_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(folder(), ec);
    });
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = (folder() / "input.las").string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    const LasHeader header = read_las_header(path);
    const PointCloud cloud = read_las(path);
    const bool rgb = header.point_format == 2 || header.point_format == 3 || header.point_format == 5 ||
                     header.point_format >= 7 && header.point_format != 9;
    if (cloud.size() != header.points || cloud.colors.size() != (rgb ? cloud.size() : 0) ||
        !cloud.origin.allFinite()) {
      std::fprintf(stderr, "las_fuzzer: %zu points and %zu colours read, the header promised %llu of format %d\n",
                   cloud.size(), cloud.colors.size(), static_cast<unsigned long long>(header.points),
                   header.point_format);
      std::abort();
    }
    for (const Vec3f& p : cloud.positions)
      if (!p.allFinite()) {
        std::fprintf(stderr, "las_fuzzer: a point is not finite\n");
        std::abort();
      }
  } catch (const InputError& e) {
    static const bool verbose = std::getenv("LAS_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "las_fuzzer: InputError: %s\n", e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "las_fuzzer: a non-InputError escaped: %s\n", e.what());
    std::abort();
  }
  return 0;
}
