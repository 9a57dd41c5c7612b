// The command line's contract: --version, --quiet, --json, exit codes, and
// the cases that must fail with a message, a documented code and no file.
#include <scan2lod/io/mesh_file.h>
#include "test_support.h"

#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
using testing::CliRun;
using testing::exit_code;
using testing::run_cli;


fs::path scratch() { return testing::scratch_folder("cli_contract"); }

std::string bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(CliContract, VersionAndExitCodesAreDocumented) {
  CliRun r = run_cli("--version");
  EXPECT_EQ(exit_code(r), 0);
  EXPECT_EQ(r.output.rfind("scan2lod 0.", 0), 0u) << r.output;
  EXPECT_NE(r.output.find("model format"), std::string::npos) << r.output;
  r = run_cli("--help");
  EXPECT_EQ(exit_code(r), 0);
  EXPECT_NE(r.output.find("Exit codes: 0 done; 1 "), std::string::npos) << r.output;
  // Usage errors: 2, whatever CLI11 rule failed.
  for (const std::string args : {"extract", "extract --percent", "extract m.mco -o x.ply --nonsense",
                                 "frobnicate", "extract m.mco -o x.ply --percent abc"}) {
    r = run_cli(args);
    EXPECT_EQ(exit_code(r), 2) << args << ": " << r.output;
  }
  // Refused input: 1.
  r = run_cli("extract " + (scratch() / "missing.mco").string() + " --percent 5 -o " + (scratch() / "x.ply").string());
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_NE(r.output.find("missing.mco"), std::string::npos) << r.output;
}

TEST(CliContract, QuietIsSilentAndJsonStillAnswers) {
  const std::string model = testing::bunny_model().string();
  const fs::path out = scratch() / "quiet.ply";
  for (const std::string& cmd : {"extract " + model + " --percent 10 -o " + out.string(),
                                "export " + model + " --levels 50,5 -o " + (scratch() / "quiet.glb").string(),
                                "info " + model,
                                "reconstruct " + testing::bunny_scans() + " -r 32 -o " + out.string()}) {
    CliRun r = run_cli(cmd + " --quiet");
    EXPECT_EQ(exit_code(r), 0) << cmd << ": " << r.output;
    EXPECT_EQ(r.output, "") << cmd;
    r = run_cli(cmd + " -q --json", /*merge_stderr=*/false);
    EXPECT_EQ(exit_code(r), 0) << cmd;
    EXPECT_TRUE(nlohmann::json::accept(r.output)) << cmd << ": " << r.output;
  }
  // Every command that produces something answers --json.
  const fs::path scans = scratch() / "scans";
  for (const std::string& cmd :
       {"build " + testing::bunny_scans() + " -r 32 -o " + (scratch() / "j.mco").string(),
        "convert " + testing::bunny_scans() + " -o " + scans.string(),
        "compare " + out.string() + " " + out.string()}) {
    const CliRun r = run_cli(cmd + " --json", false);
    EXPECT_EQ(exit_code(r), 0) << cmd << ": " << r.output;
    EXPECT_TRUE(nlohmann::json::accept(r.output)) << cmd << ": " << r.output;
  }
}

TEST(CliContract, AnEmptyLevelIsAnError) {
  const std::string model = testing::bunny_model().string();
  const fs::path out = scratch() / "empty.ply";
  CliRun r = run_cli("extract " + model + " --triangles 0 -o " + out.string());
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_NE(r.output.find("no level has at most 0 triangles"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("coarsest level offered has"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // The octree's root level can be empty too: asked for by percent 0.
  r = run_cli("extract " + model + " --structure octree --percent 0 -o " + out.string());
  if (exit_code(r) == 0) {
    EXPECT_GT(read_mesh(out.string()).triangles.size(), 0u);
  } else {
    EXPECT_EQ(exit_code(r), 1) << r.output;
    EXPECT_FALSE(fs::exists(out));
  }
  r = run_cli("export " + model + " --triangles 1000,0 -o " + (scratch() / "empty.glb").string());
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_FALSE(fs::exists(scratch() / "empty.glb"));
}

// --triangles T meets T within 10 %; --at-most makes it a cap. The bunny at
// R = 64 has no octree level between 230 and 694 triangles.
TEST(CliContract, ATriangleBudgetIsMetWithinTenPercentOrStrictly) {
  const std::string model = testing::bunny_model().string();
  const fs::path out = scratch() / "budget.ply";
  auto triangles = [&](const std::string& args) {
    const CliRun r = run_cli("extract " + model + " " + args + " --json -q -o " + out.string(), false);
    EXPECT_EQ(exit_code(r), 0) << args << ": " << r.output;
    return nlohmann::json::parse(r.output).at("triangles").get<long long>();
  };
  for (const std::string structure : {"octree", "clusters"})
    for (const long long budget : {650LL, 1000LL, 3000LL}) {
      const std::string ask = "--structure " + structure + " --triangles " + std::to_string(budget);
      const long long strict = triangles(ask + " --at-most"), got = triangles(ask);
      EXPECT_LE(strict, budget) << ask;
      EXPECT_TRUE(got == strict || (10 * strict < 9 * budget && got > budget && 10 * got <= 11 * budget))
          << ask << ": " << got << " (at most: " << strict << ")";
      if (structure == "octree" && budget == 650) {
        EXPECT_GT(got, budget) << "the level with the ears, 694";
      }
    }
  const CliRun r = run_cli("extract " + model + " --at-most -o " + out.string());
  EXPECT_EQ(exit_code(r), 2) << "--at-most needs --triangles: " << r.output;
}

TEST(CliContract, AnInputIsNeverOverwritten) {
  const fs::path dir = scratch() / "inputs";
  fs::create_directories(dir);
  const fs::path model = dir / "m.mco";
  fs::copy_file(testing::bunny_model(), model, fs::copy_options::overwrite_existing);
  const std::string before = bytes_of(model);
  // The same file by its own name and by another spelling of it.
  for (const std::string& out : {model.string(), (dir / "." / "m.mco").string()}) {
    CliRun r = run_cli("build " + model.string() + " -o " + out);
    EXPECT_EQ(exit_code(r), 1) << r.output;
    EXPECT_NE(r.output.find("is also an input"), std::string::npos) << r.output;
  }
  const fs::path mesh = dir / "mesh.ply";
  CliRun r = run_cli("extract " + model.string() + " --percent 20 -o " + mesh.string() + " -q");
  ASSERT_EQ(exit_code(r), 0) << r.output;
  const std::string mesh_before = bytes_of(mesh);
  r = run_cli("reconstruct " + mesh.string() + " -r 32 -o " + mesh.string());
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_NE(r.output.find("is also an input"), std::string::npos) << r.output;
  EXPECT_EQ(bytes_of(model), before);
  EXPECT_EQ(bytes_of(mesh), mesh_before);
}

TEST(CliContract, AFolderInTheWayIsNamed) {
  const fs::path folder = scratch() / "taken.ply";
  fs::create_directories(folder);
  const CliRun r = run_cli("extract " + testing::bunny_model().string() + " --percent 20 -o " + folder.string());
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_NE(r.output.find("is a folder"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Success"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_empty(folder));
}

TEST(CliContract, OffscreenViewWithoutAScriptIsRefused) {
  const CliRun r = run_cli("view " + testing::bunny_model().string() + " --offscreen");
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_NE(r.output.find("--offscreen needs --script"), std::string::npos) << r.output;
}

TEST(CliContract, ObjKeepsVertexColours) {
  TriangleMesh mesh;
  mesh.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, 0, 1)};
  mesh.colors = {Rgb{255, 0, 0}, Rgb{0, 255, 0}, Rgb{0, 0, 255}, Rgb{17, 128, 251}};
  mesh.normals = {Vec3f(0, 0, 1), Vec3f(0, 0, 1), Vec3f(0, 0, 1), Vec3f(1, 0, 0)};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}};
  const fs::path obj = scratch() / "coloured.obj";
  write_mesh(obj.string(), mesh);
  const TriangleMesh back = read_mesh(obj.string());
  ASSERT_EQ(back.colors.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(back.colors[i], mesh.colors[i]) << i;
    EXPECT_EQ(back.positions[i], mesh.positions[i]) << i;
    EXPECT_EQ(back.normals[i], mesh.normals[i]) << i;
  }
  EXPECT_EQ(back.triangles, mesh.triangles);
}

// Every mesh format read_mesh reads is an input the README promises.
TEST(CliContract, AVtpMeshIsAnInput) {
  const fs::path dir = scratch() / "vtp";
  fs::create_directories(dir);
  const CliRun r0 = run_cli("extract " + testing::bunny_model().string() + " --percent 100 -q -o " +
                            (dir / "bunny.vtp").string());
  ASSERT_EQ(exit_code(r0), 0) << r0.output;
  const CliRun r = run_cli("reconstruct " + (dir / "bunny.vtp").string() + " -r 64 -q -o " +
                           (dir / "again.ply").string());
  EXPECT_EQ(exit_code(r), 0) << r.output;
  EXPECT_GT(read_mesh((dir / "again.ply").string()).triangles.size(), 1000u);
}

}  // namespace
}  // namespace scan2lod
