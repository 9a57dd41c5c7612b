// The command line: bad input gets a clear error, a non-zero exit and no
// output file; good input gets a one-line summary and the file.
#include "test_support.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace fs = std::filesystem;

namespace {

using scan2lod::testing::CliRun;
using scan2lod::testing::run_cli;

fs::path scratch() {
  const fs::path dir = scan2lod::testing::scratch_folder() / "cli";
  fs::create_directories(dir);
  return dir;
}

bool folder_has_only(const fs::path& dir, std::size_t count) {
  return std::size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator())) == count;
}

const std::string kScans = std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf";

}  // namespace

TEST(Cli, ReconstructsTheBundledBunnyWithASummary) {
  const fs::path out = scratch() / "bunny.ply";
  CliRun r = run_cli("reconstruct " + kScans + " -o " + out.string() + " --resolution 64");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("358808 points"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("triangles"), std::string::npos);
  // Piped: no progress bar drawn.
  EXPECT_EQ(r.output.find('\r'), std::string::npos);
  EXPECT_GT(fs::file_size(out), 100000u);
}

TEST(Cli, TheClosestPointDistanceKeepsItsEarlierName) {
  // --distance closest (Lee's sign x |v - p|) was spelt "seed": both give one surface, unlike hoppe's.
  std::array<std::string, 3> bytes;
  const std::array<const char*, 3> names = {"closest", "seed", "hoppe"};
  for (std::size_t i = 0; i < names.size(); ++i) {
    const fs::path out = scratch() / (std::string("distance_") + names[i] + ".ply");
    const CliRun r = run_cli("reconstruct " + kScans + " -o " + out.string() + " -r 32 -q --distance " + names[i]);
    ASSERT_EQ(r.status, 0) << r.output;
    std::ifstream in(out, std::ios::binary);
    bytes[i].assign(std::istreambuf_iterator<char>(in), {});
    EXPECT_GT(bytes[i].size(), 10000u);
  }
  EXPECT_TRUE(bytes[0] == bytes[1]);
  EXPECT_FALSE(bytes[0] == bytes[2]);
  const CliRun bad = run_cli("reconstruct " + kScans + " -o " + (scratch() / "x.ply").string() + " --distance nearest");
  EXPECT_NE(bad.output.find("expected closest, hoppe or planes"), std::string::npos) << bad.output;
}

TEST(Cli, BadInputsFailCleanlyAndWriteNothing) {
  const fs::path dir = scratch() / "bad";
  fs::create_directories(dir);
  const fs::path out = dir / "out.ply";
  std::ofstream(dir / "garbled.ply") << "ply\nformat ascii 1.0\nobj_info num_cols 2\nobj_info num_rows 1\n"
                                        "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                                        "element range_grid 2\nproperty list uchar int vertex_indices\n"
                                        "end_header\n0 0 0\n1 zero 0\n1 0\n1 1\n";
  std::ofstream(dir / "missing.conf") << "bmesh nowhere.ply 0 0 0 0 0 0 1\n";
  std::ofstream(dir / "flat.off") << "OFF\n3 1 0\n0 0 0\n0 0 0\n0 0 0\n3 0 1 2\n";
  std::ofstream(dir / "nan.off") << "OFF\n3 1 0\n0 0 0\nnan 1 0\n0 1 0\n3 0 1 2\n";
  std::ofstream(dir / "sparse.off") << "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {(dir / "garbled.ply").string(), "vertex 1"},
      {(dir / "missing.conf").string(), "nowhere.ply"},
      {(dir / "nan.off").string(), "nan.off"},
      {(dir / "flat.off").string(), "flat.off"},
      {(dir / "absent.ply").string(), "absent.ply"},
      {(dir / "sparse.off").string() + " -r 64", "no surface at resolution 64"},
      {kScans + " --resolution 100", "power of two"},
      {kScans + " --resolution 0", "power of two"},
      // Below 16 the grid's 8 cubes of padding leave no room (R = 8 divided by zero).
      {kScans + " --resolution 8", "power of two from 16"},
      {kScans + " --distance magic", "distance method"},
  };
  for (const Case& c : cases) {
    CliRun r = run_cli("reconstruct " + c.args + " -o " + out.string() + " -q");
    EXPECT_NE(r.status, 0) << c.args;
    EXPECT_NE(r.output.find("error"), std::string::npos) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << ": " << r.output;
    EXPECT_EQ(r.output.find("Segmentation"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out)) << c.args;
    EXPECT_TRUE(folder_has_only(dir, 5)) << "a temporary file was left behind by " << c.args;
  }
  // An output format nobody can write is refused before any work is lost.
  CliRun r = run_cli("reconstruct " + kScans + " -o " + (dir / "out.xyz").string() + " -r 16 -q");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find(".xyz"), std::string::npos) << r.output;
  EXPECT_TRUE(folder_has_only(dir, 5));
}

TEST(Cli, ConvertWritesABinaryScanSet) {
  const fs::path dir = scratch() / "converted";
  CliRun r = run_cli("convert " + kScans + " -o " + dir.string() + " --conf bun.conf");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("10 scans"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "bun.conf"));
  EXPECT_TRUE(fs::exists(dir / "ear_back.ply"));
}
