// The commands that only read models start without PCL, VTK or Open3D: the
// shared objects the dynamic loader initialises are counted (LD_DEBUG=libs),
// and the others run all the same through scan2lod-full.
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using scan2lod::testing::bunny_model;
using scan2lod::testing::run_shell;

// The shared objects the loader initialised for `scan2lod ARGS`, by file name.
std::vector<std::string> initialised(const std::string& args) {
  const scan2lod::testing::CliRun r =
      run_shell("LD_DEBUG=libs " + std::string(SCAN2LOD_CLI) + " " + args + " 2>&1 >/dev/null");
  std::vector<std::string> objects;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    const std::size_t at = line.find("calling init: ");
    if (at != std::string::npos) objects.push_back(fs::path(line.substr(at + 14)).filename().string());
  }
  return objects;
}

std::string heavy_among(const std::vector<std::string>& objects) {
  std::string found;
  for (const std::string& o : objects)
    if (o.rfind("libpcl", 0) == 0 || o.rfind("libvtk", 0) == 0 || o.rfind("libOpen3D", 0) == 0) found += o + " ";
  return found;
}

}  // namespace

TEST(LeanStart, ModelCommandsMapFewSharedObjectsAndNoHeavyLibrary) {
  const fs::path dir = scan2lod::testing::scratch_folder("lean");
  const std::string model = bunny_model().string();
  for (const std::string& args :
       {"info " + model, "extract " + model + " --triangles 2000 -o " + (dir / "cut.ply").string() + " -q",
        "export " + model + " --format 3dtiles -o " + (dir / "tiles").string() + " -q"}) {
    const std::vector<std::string> objects = initialised(args);
    EXPECT_GT(objects.size(), 3u) << args;  // libc, libstdc++, ... : the count is real
    EXPECT_LE(objects.size(), 40u) << args;
    EXPECT_EQ(heavy_among(objects), "") << args;
  }
  EXPECT_TRUE(fs::exists(dir / "cut.ply"));
  EXPECT_TRUE(fs::exists(dir / "tiles" / "tileset.json"));
}

TEST(LeanStart, OtherCommandsAndVtpFilesRunInTheFullProgram) {
  const fs::path dir = scan2lod::testing::scratch_folder("lean_full");
  const std::string model = bunny_model().string();
  // A .vtp output needs VTK: the same command runs in scan2lod-full.
  const std::vector<std::string> vtp =
      initialised("extract " + model + " --triangles 2000 -o " + (dir / "cut.vtp").string() + " -q");
  EXPECT_NE(heavy_among(vtp), "");
  EXPECT_TRUE(fs::exists(dir / "cut.vtp"));
  // A command of the full program, with its messages and exit codes.
  const scan2lod::testing::CliRun r = scan2lod::testing::run_cli("compare " + (dir / "cut.vtp").string() + " " +
                                                                 (dir / "missing.ply").string());
  EXPECT_EQ(scan2lod::testing::exit_code(r), 1);
  EXPECT_NE(r.output.find("missing.ply"), std::string::npos) << r.output;
}
