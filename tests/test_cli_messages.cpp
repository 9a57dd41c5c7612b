// What the command line says (issue 38): every usage error as
// "scan2lod: error: ..." with exit code 2, a level that misses its --percent
// warned like one that misses its --triangles, degenerate cameras and flags
// that would be ignored refused, and summaries that name what was written.
#include <scan2lod/lod/level_budget.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include "test_support.h"

#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
using testing::CliRun;
using testing::exit_code;
using testing::run_cli;


fs::path scratch() { return testing::scratch_folder("cli_messages"); }

bool has(const CliRun& r, const std::string& text) { return r.output.find(text) != std::string::npos; }

std::size_t count_of(const std::string& text, const std::string& word) {
  std::size_t n = 0;
  for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) ++n;
  return n;
}

// `scan2lod ARGS` run from `folder`, stderr merged: for paths as a user types them.
CliRun run_cli_in(const fs::path& folder, const std::string& args) {
  return testing::run_shell("cd '" + folder.string() + "' && " + SCAN2LOD_CLI + " " + args + " 2>&1");
}

// Whether `text` holds `ext` as a whole extension (".xyz" is not in ".xyzn").
bool names_extension(const std::string& text, const std::string& ext) {
  for (std::size_t at = text.find(ext); at != std::string::npos; at = text.find(ext, at + 1)) {
    const std::size_t end = at + ext.size();
    if (end == text.size() || !std::isalnum(static_cast<unsigned char>(text[end]))) return true;
  }
  return false;
}

std::string model() { return testing::bunny_model().string(); }

// The percentages in 1..99 whose cluster cut misses P % of the full triangles
// by more than 10 %, and those it meets (the cut with at most P %).
void cluster_percents(std::vector<int>* missed, std::vector<int>* met) {
  const LodModel m = load_model(model());
  const std::int64_t full = m.clusters->full_triangles;
  LevelExtractor extractor(m, LodStructure::kClusters);
  for (int p = 1; p < 100; ++p) {
    const auto want = std::int64_t(std::floor(p / 100.0 * double(full)));
    LevelRequest stored = LevelRequest::at_percent(p);
    stored.refine = false;
    const std::int64_t got = std::int64_t(extractor.extract(stored).triangles.size());
    (meets_budget(got, want) ? met : missed)->push_back(p);
  }
}

}  // namespace

// 1. --percent misses like --triangles does: a warning naming both percents.
// The stored cuts (--stored-cut) miss most: refined ones miss only where no
// finer stored cut is near enough to refine (lod/clusters/cut_refinement.h).
TEST(CliMessages, APercentNoLevelMeetsIsWarned) {
  std::vector<int> missed, met;
  cluster_percents(&missed, &met);
  ASSERT_FALSE(missed.empty()) << "every percentage has a cut within 10 %";
  ASSERT_FALSE(met.empty());
  const LodModel m = load_model(model());
  const std::int64_t full = m.clusters->full_triangles;
  const int p = missed.back();
  const std::string out = (scratch() / "percent.ply").string();
  CliRun r = run_cli("extract " + model() + " --structure clusters --stored-cut --percent " + std::to_string(p) + " -o " + out);
  ASSERT_EQ(exit_code(r), 0) << r.output;
  LevelExtractor extractor(m, LodStructure::kClusters);
  LevelRequest stored = LevelRequest::at_percent(p);
  stored.refine = false;
  const std::size_t got = extractor.extract(stored).triangles.size();
  char got_percent[32];
  std::snprintf(got_percent, sizeof got_percent, "%.1f %%", 100.0 * double(got) / double(full));
  for (const std::string& word : {"scan2lod: warning: --percent " + std::to_string(p) + " asks for " +
                                      std::to_string(p) + " %",
                                  "got " + std::to_string(got) + " triangles (" + got_percent + ")"})
    EXPECT_TRUE(has(r, word)) << word << " missing from: " << r.output;
  // A percentage a cut meets: no warning; --quiet: none either.
  r = run_cli("extract " + model() + " --structure clusters --stored-cut --percent " + std::to_string(met.back()) + " -o " + out);
  ASSERT_EQ(exit_code(r), 0) << r.output;
  EXPECT_FALSE(has(r, "warning")) << r.output;
  r = run_cli("extract " + model() + " --structure clusters --stored-cut --percent " + std::to_string(p) + " -q -o " + out);
  EXPECT_EQ(r.output, "");
  // With --json the warning is part of the one object printed.
  r = run_cli("extract " + model() + " --structure clusters --stored-cut --percent " + std::to_string(p) + " --json -o " + out);
  ASSERT_EQ(exit_code(r), 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j.at("warnings").size(), 1u) << r.output;
  EXPECT_EQ(j["warnings"][0].get<std::string>().rfind("--percent " + std::to_string(p), 0), 0u) << r.output;
  // export says it for its --levels too.
  r = run_cli("export " + model() + " --structure clusters --stored-cuts --levels " + std::to_string(p) + " -o " +
              (scratch() / "percent.glb").string());
  ASSERT_EQ(exit_code(r), 0) << r.output;
  EXPECT_TRUE(has(r, "scan2lod: warning: --levels " + std::to_string(p) + " asks for")) << r.output;
}

// 2. --threads: a negative count is a usage error naming it; more than the
// machine has is lowered to its cores with a warning, for every command.
TEST(CliMessages, ThreadsAreACountOfCoresTheMachineHas) {
  const std::string conf = testing::bunny_scans();
  const std::string mesh = (scratch() / "threads.ply").string();
  for (const std::string& args :
       {"reconstruct " + conf + " -o " + mesh + " --threads -1", "build " + conf + " -o " +
                                                                      (scratch() / "threads.mco").string() + " -j -1",
        "convert " + conf + " -o " + (scratch() / "threads_scans").string() + " --threads -1"}) {
    const CliRun r = run_cli(args);
    EXPECT_EQ(exit_code(r), 2) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("scan2lod: error: --threads", 0), 0u) << args << ": " << r.output;
    EXPECT_TRUE(has(r, "-1")) << args << ": " << r.output;
  }
  EXPECT_FALSE(fs::exists(mesh));
  const CliRun r = run_cli("reconstruct " + conf + " -r 32 -o " + mesh + " --threads 999");
  EXPECT_EQ(exit_code(r), 0) << r.output;
  EXPECT_TRUE(has(r, "scan2lod: warning: --threads 999 is more than this machine's")) << r.output;
  EXPECT_TRUE(fs::exists(mesh));
  const CliRun help = run_cli("convert --help");
  EXPECT_TRUE(has(help, "above the machine's cores is lowered")) << help.output;
}

// 3. CLI11's own errors carry the prefix every other error has, and exit 2.
TEST(CliMessages, EveryUsageErrorSaysScan2lodError) {
  const std::string out = (scratch() / "usage.ply").string();
  for (const std::string& args : std::vector<std::string>{
           "extract " + model() + " --percent abc -o " + out, "extract",
           "extract " + model() + " --percent 5 --nonsense -o " + out, "", "-q",
           "export " + model() + " --levels 5,x -o " + out}) {
    const CliRun r = run_cli(args);
    EXPECT_EQ(exit_code(r), 2) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("scan2lod: error: ", 0), 0u) << args << ": " << r.output;
  }
  const CliRun r = run_cli("extract " + model() + " --percent abc -o " + out);
  EXPECT_TRUE(has(r, "--percent")) << r.output;
  EXPECT_TRUE(has(r, "'abc'")) << r.output;
}

// 4. A mistyped command is named, with the nearest command when one is close.
TEST(CliMessages, AMistypedCommandIsNamed) {
  CliRun r = run_cli("extrct " + model() + " --percent 5 -o x.ply");
  EXPECT_EQ(exit_code(r), 2) << r.output;
  EXPECT_TRUE(has(r, "scan2lod: error: unknown command 'extrct'")) << r.output;
  EXPECT_TRUE(has(r, "did you mean 'extract'")) << r.output;
  r = run_cli("-q biuld x.conf -o x.mco");
  EXPECT_EQ(exit_code(r), 2) << r.output;
  EXPECT_TRUE(has(r, "did you mean 'build'")) << r.output;
  r = run_cli("frobnicate");
  EXPECT_EQ(exit_code(r), 2) << r.output;
  EXPECT_TRUE(has(r, "unknown command 'frobnicate'")) << r.output;
  EXPECT_FALSE(has(r, "did you mean")) << r.output;
}

// 5. A camera with no frame is refused, naming --camera and its values.
TEST(CliMessages, ADegenerateCameraIsRefused) {
  const fs::path out = scratch() / "camera.ply";
  struct Case {
    std::string camera, expect;
  };
  for (const Case& c : std::vector<Case>{{"1,2,3,1,2,3,0,1,0", "the eye 1,2,3 is the target 1,2,3"},
                                         {"0,0,1,0,0,0,0,0,2", "up 0,0,2 is parallel to the view direction 0,0,-1"},
                                         {"0,0,1,0,0,0,0,0,0", "up 0,0,0 has no direction"}}) {
    const CliRun r = run_cli("extract " + model() + " --camera " + c.camera + " -o " + out.string());
    EXPECT_EQ(exit_code(r), 1) << c.camera << ": " << r.output;
    EXPECT_TRUE(has(r, "scan2lod: error: --camera: " + c.expect)) << c.camera << ": " << r.output;
    EXPECT_FALSE(fs::exists(out)) << c.camera;
  }
  const CliRun r = run_cli("extract " + model() + " --camera 0,0,1,0,0,0,0,1,0 -q -o " + out.string());
  EXPECT_EQ(exit_code(r), 0) << r.output;
}

// 6. An out-of-range --fov is named with the value given.
TEST(CliMessages, AFovOutOfRangeNamesTheValue) {
  const std::string out = (scratch() / "fov.ply").string();
  for (const char* value : {"0", "180", "-5.5"}) {
    const std::string fov = value;
    const CliRun r = run_cli("extract " + model() + " --camera 0,0,1,0,0,0,0,1,0 --fov=" + fov + " -o " + out);
    EXPECT_EQ(exit_code(r), 1) << r.output;
    EXPECT_TRUE(has(r, "--fov must be in (0, 180) degrees, got " + fov)) << r.output;
  }
}

// 7. A camera's flags without --camera (and glTF's without glTF) would be
// ignored: a usage error instead.
TEST(CliMessages, AFlagThatWouldBeIgnoredIsRefused) {
  const fs::path out = scratch() / "ignored.ply";
  for (const char* value : {"--fov 30", "--height 500", "--pixel-error 2"}) {
    const std::string flag = value;
    const CliRun r = run_cli("extract " + model() + " --percent 50 " + flag + " -o " + out.string());
    EXPECT_EQ(exit_code(r), 2) << flag << ": " << r.output;
    const std::string name = flag.substr(0, flag.find(' '));
    EXPECT_TRUE(has(r, "scan2lod: error: " + name + ": applies to --camera only; --percent")) << r.output;
  }
  const CliRun stored = run_cli("extract " + model() + " --error 0.001 --stored-cut -o " + out.string());
  EXPECT_EQ(exit_code(stored), 2) << stored.output;
  EXPECT_TRUE(has(stored, "scan2lod: error: --stored-cut: applies to --percent and --triangles only")) << stored.output;
  EXPECT_FALSE(fs::exists(out));
  const CliRun r = run_cli("export " + model() + " --pixel-error 2 -o " + out.string());
  EXPECT_EQ(exit_code(r), 2) << r.output;
  EXPECT_TRUE(has(r, "scan2lod: error: --pixel-error: applies to a glTF output only")) << r.output;
}

// 8. export's summary names the files written; an output without a known
// extension is refused before any work, by the name given.
TEST(CliMessages, ExportNamesItsFiles) {
  const fs::path dir = scratch() / "export";
  fs::create_directories(dir / "ex");
  CliRun r = run_cli_in(dir, "export " + model() + " --levels 100,5 -o chain.obj");
  ASSERT_EQ(exit_code(r), 0) << r.output;
  EXPECT_TRUE(has(r, "-> chain_LOD0.obj, chain_LOD1.obj\n")) << r.output;
  EXPECT_TRUE(fs::exists(dir / "chain_LOD1.obj"));
  r = run_cli_in(dir, "export " + model() + " -o ex/noext");
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_TRUE(has(r, "scan2lod: error: ex/noext: has no extension")) << r.output;
  EXPECT_TRUE(has(r, ".glb or .gltf")) << r.output;
  EXPECT_FALSE(has(r, "noext_LOD0")) << r.output;
  r = run_cli_in(dir, "export " + model() + " -o ex/n.foo");
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_TRUE(has(r, "scan2lod: error: ex/n.foo: unknown extension '.foo'")) << r.output;
  EXPECT_TRUE(fs::is_empty(dir / "ex"));
}

// 9. Paths are printed as the user wrote them. Disabled until
// acquisition/load_inputs.cpp (conf_listing) stops making the .conf's path
// relative to the working folder.
TEST(CliMessages, AnAbsoluteInputIsNamedAsTyped) {
  const fs::path bunny = fs::path(SCAN2LOD_SOURCE_DIR) / "data" / "bunny";
  const CliRun r = run_cli_in(scratch(), "build " + (bunny / "bun000.ply").string() + " " +
                                             (bunny / "bun045.ply").string() + " -o loose.mco");
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_TRUE(has(r, "Give " + (bunny / "bun.conf").string() + ",")) << r.output;
  EXPECT_FALSE(has(r, "../")) << r.output;
}

// 10. The inputs help lists what the loader reads (load_inputs.cpp).
TEST(CliMessages, HelpListsTheInputsTheLoaderReads) {
  for (const std::string command : {"reconstruct", "build"}) {
    const CliRun r = run_cli(command + " --help");
    ASSERT_EQ(exit_code(r), 0) << r.output;
    const std::size_t from = r.output.find("inputs"), to = r.output.find("-o,--output");
    ASSERT_LT(from, to) << r.output;
    const std::string inputs = r.output.substr(from, to - from);
    for (const std::string ext : {".conf", ".pcd", ".xyz", ".xyzn", ".xyzrgb", ".pts", ".ply", ".obj", ".off", ".stl",
                                  ".vtp", ".glb", ".gltf"})
      EXPECT_TRUE(names_extension(inputs, ext)) << command << ": " << ext << " missing from " << inputs;
  }
}

// 10. README says where info --json puts offered_levels: under "octree" only.
TEST(CliMessages, ReadmeSaysWhereOfferedLevelsIs) {
  const CliRun r = run_cli("info " + model() + " --json", false);
  ASSERT_EQ(exit_code(r), 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_TRUE(j.at("octree").contains("offered_levels"));
  EXPECT_FALSE(j.contains("offered_levels"));
  std::ifstream readme(std::string(SCAN2LOD_SOURCE_DIR) + "/README.md");
  std::string line, documented;
  while (std::getline(readme, line))
    if (line.find("offered_levels") != std::string::npos) documented += line;
  EXPECT_NE(documented.find("`octree.offered_levels`"), std::string::npos) << documented;
}

// 10. export --levels 10,10 writes the level once and warns once.
TEST(CliMessages, ARepeatedLevelIsWrittenOnce) {
  const std::string out = (scratch() / "repeat.glb").string();
  CliRun r = run_cli("export " + model() + " --levels 50,10,10,50,5 -q --json -o " + out);
  ASSERT_EQ(exit_code(r), 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j.at("levels").size(), 3u) << r.output;
  EXPECT_EQ(j.at("warnings")[0], "--levels repeats 10, 50; each level is written once") << r.output;
  r = run_cli("export " + model() + " --levels 50,10,10,50,5 -o " + out);
  ASSERT_EQ(exit_code(r), 0) << r.output;
  EXPECT_EQ(count_of(r.output, "repeats"), 1u) << r.output;
  EXPECT_TRUE(has(r, "scan2lod: warning: --levels repeats 10, 50; each level is written once")) << r.output;
  EXPECT_EQ(count_of(r.output, "LOD"), 3u) << r.output;
}

}  // namespace scan2lod
