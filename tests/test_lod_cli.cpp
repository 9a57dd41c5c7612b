// The LOD commands (build, info, extract) through the real binary: the model
// built from the bundled bunny reports its levels, extraction gives the mesh
// sizes info promised, and bad input ends in a clear error and no file.
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/octree/lod_array.h>

#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;

namespace {

using scan2lod::testing::CliRun;
using scan2lod::testing::run_cli;

fs::path scratch() { return scan2lod::testing::scratch_folder("lod_cli"); }

const std::string kScans = scan2lod::testing::bunny_scans();

using scan2lod::testing::bunny_model;

std::size_t files_in(const fs::path& dir) {
  return std::size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

}  // namespace

TEST(LodCli, BuildPrintsAOneLineSummary) {
  const fs::path model = scratch() / "summary.mco";
  const CliRun r = run_cli("build " + kScans + " -o " + model.string() + " -r 32");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* word : {"358808 points", "nodes", "expansions", "triangles at 100%", "reconstruct", "octree",
                           "clusters"})
    EXPECT_NE(r.output.find(word), std::string::npos) << word << " missing from: " << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_GT(fs::file_size(model), 10000u);
}

TEST(LodCli, InfoAndExtractAgreeOnTheBunny) {
  const fs::path& model = bunny_model();
  ASSERT_TRUE(fs::exists(model));
  const CliRun info = run_cli("info " + model.string() + " --json", false);
  ASSERT_EQ(info.status, 0) << info.output;
  const nlohmann::json j = nlohmann::json::parse(info.output);
  EXPECT_EQ(j.at("resolution").get<int>(), 64);
  EXPECT_EQ(j.at("depth").get<int>(), 6);
  const auto per_level = j.at("nodes_per_level").get<std::vector<std::size_t>>();
  ASSERT_EQ(per_level.size(), 7u);
  EXPECT_EQ(per_level[0], 1u);
  for (std::size_t l = 1; l < per_level.size(); ++l) EXPECT_GE(per_level[l], per_level[l - 1]) << "level " << l;
  EXPECT_EQ(j.at("leaves").get<std::size_t>(), per_level.back());
  std::size_t nodes = 0;
  for (std::size_t c : per_level) nodes += c;
  EXPECT_EQ(j.at("nodes").get<std::size_t>(), nodes);
  EXPECT_EQ(j.at("expansions").get<std::size_t>(), nodes - per_level.back());

  const auto& lods = j.at("levels_of_detail");
  ASSERT_EQ(lods.size(), 8u);
  const double percents[] = {100, 80, 60, 40, 20, 10, 5, 1};
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(lods[i].at("percent").get<double>(), percents[i]);
    EXPECT_GT(lods[i].at("vertices").get<std::size_t>(), 0u);
    if (i > 0) {
      EXPECT_LT(lods[i].at("priority").get<std::size_t>(), lods[i - 1].at("priority").get<std::size_t>());
      EXPECT_LE(lods[i].at("triangles").get<std::size_t>(), lods[i - 1].at("triangles").get<std::size_t>())
          << percents[i] << "% has more triangles than " << percents[i - 1] << "%";
    }
  }
  EXPECT_EQ(lods[0].at("priority").get<std::size_t>(), j.at("expansions").get<std::size_t>());
  // No pinned prefix: the bunny's open base coarsens with its nodes, and
  // the 1 % level has about 1 % of the triangles.
  EXPECT_EQ(j.at("pinned").get<std::size_t>(), 0u);
  EXPECT_LE(lods[7].at("triangles").get<std::size_t>(), lods[0].at("triangles").get<std::size_t>() / 50);
  const std::size_t full = lods[0].at("triangles").get<std::size_t>(), fifth = lods[4].at("triangles").get<std::size_t>();
  EXPECT_GT(full, 2 * fifth);
  EXPECT_GT(full, 10000u);

  // --percent 100 writes the full mesh that info counted.
  const fs::path out = scratch() / "full.ply";
  const CliRun x =
      run_cli("extract " + model.string() + " --structure octree --percent 100 -o " + out.string() + " --json", false);
  ASSERT_EQ(x.status, 0) << x.output;
  const nlohmann::json e = nlohmann::json::parse(x.output);
  for (const char* key : {"priority", "triangles", "vertices", "extract_seconds"})
    EXPECT_TRUE(e.contains(key)) << key << " missing from " << x.output;
  EXPECT_EQ(e.at("priority").get<std::size_t>(), lods[0].at("priority").get<std::size_t>());
  EXPECT_EQ(e.at("triangles").get<std::size_t>(), full);
  EXPECT_EQ(e.at("vertices").get<std::size_t>(), lods[0].at("vertices").get<std::size_t>());
  EXPECT_GE(e.at("extract_seconds").get<double>(), 0.0);
  EXPECT_LT(e.at("extract_seconds").get<double>(), 1.0);
  const scan2lod::TriangleMesh mesh = scan2lod::read_mesh(out.string());
  EXPECT_EQ(mesh.triangles.size(), full);
  EXPECT_EQ(mesh.positions.size(), e.at("vertices").get<std::size_t>());

  // --triangles takes the finest level within the budget; --priority is exact.
  const std::size_t budget = fifth;
  const CliRun t = run_cli("extract " + model.string() + " --structure octree --triangles " + std::to_string(budget) + " -o " +
                           (scratch() / "budget.obj").string() + " --json",
                       false);
  ASSERT_EQ(t.status, 0) << t.output;
  const nlohmann::json tj = nlohmann::json::parse(t.output);
  EXPECT_LE(tj.at("triangles").get<std::size_t>(), budget);
  EXPECT_GE(tj.at("priority").get<std::size_t>(), lods[4].at("priority").get<std::size_t>());
  // The root's level is empty here (an error, not an empty file); one expansion is not.
  const CliRun root = run_cli("extract " + model.string() + " --priority 0 -o " + (scratch() / "root.off").string());
  EXPECT_NE(root.status, 0);
  EXPECT_NE(root.output.find("has no triangles"), std::string::npos) << root.output;
  const CliRun p = run_cli("extract " + model.string() + " --priority 1 -o " + (scratch() / "root.off").string() + " --json",
                       false);
  ASSERT_EQ(p.status, 0) << p.output;
  EXPECT_EQ(nlohmann::json::parse(p.output).at("priority").get<std::size_t>(), 1u);
  EXPECT_LT(nlohmann::json::parse(p.output).at("triangles").get<std::size_t>(), 20u);

  // Without --json: a one-line summary and a table.
  const CliRun plain =
      run_cli("extract " + model.string() + " --structure octree --percent 20 -o " + (scratch() / "p20.ply").string());
  ASSERT_EQ(plain.status, 0) << plain.output;
  EXPECT_NE(plain.output.find(std::to_string(fifth) + " triangles"), std::string::npos) << plain.output;
  const CliRun table = run_cli("info " + model.string());
  ASSERT_EQ(table.status, 0) << table.output;
  EXPECT_NE(table.output.find("LOD %"), std::string::npos) << table.output;
  EXPECT_NE(table.output.find(std::to_string(full)), std::string::npos) << table.output;
}

// A budget that falls inside one of the octree's steps gets the nearest level
// below it and a warning that names the step;
// a budget an offered level meets gets no warning; --quiet silences it.
TEST(LodCli, ABudgetNoLevelMeetsIsReported) {
  const fs::path& model = bunny_model();
  ASSERT_TRUE(fs::exists(model));
  const scan2lod::LodModel loaded = scan2lod::load_model(model.string());
  const scan2lod::LodArray& lod = loaded.octree->lod;
  // The largest relative step between offered levels (the R = 64 bunny's
  // ears come in one step, 230 -> 694 triangles).
  std::int64_t under = 0, over = 0;
  std::int64_t previous = -1;
  for (const std::size_t p : scan2lod::monotone_priorities(lod)) {
    const std::int64_t count = lod.accumulated[p];
    if (previous > 0 && (over == 0 || double(count) / double(previous) > double(over) / double(under)))
      under = previous, over = count;
    previous = count;
  }
  ASSERT_GT(double(over) / double(under), 1.1 / 0.9) << "no step a budget could fall into: " << under << " -> " << over;
  const std::int64_t budget = std::int64_t(std::sqrt(double(under) * double(over)));  // > 10 % from both
  const std::string out = (scratch() / "step.ply").string();
  const CliRun r = run_cli("extract " + model.string() + " --structure octree --triangles " + std::to_string(budget) +
                           " -o " + out);
  ASSERT_EQ(r.status, 0) << r.output;
  for (const std::string& word : std::vector<std::string>{
           "warning", "within 10 % of " + std::to_string(budget) + " triangles",
           "from " + std::to_string(under) + " to " + std::to_string(over), "took the one with " + std::to_string(under)})
    EXPECT_NE(r.output.find(word), std::string::npos) << word << " missing from: " << r.output;
  EXPECT_EQ(scan2lod::read_mesh(out).triangles.size(), std::size_t(under));
  const CliRun quiet = run_cli("extract " + model.string() + " --structure octree --triangles " +
                               std::to_string(budget) + " -o " + out + " -q");
  ASSERT_EQ(quiet.status, 0) << quiet.output;
  EXPECT_EQ(quiet.output, "");
  // export says it per level too.
  const CliRun chain = run_cli("export " + model.string() + " --structure octree --triangles " +
                               std::to_string(budget) + "," + std::to_string(over) + " -o " +
                               (scratch() / "step.glb").string());
  ASSERT_EQ(chain.status, 0) << chain.output;
  std::size_t warnings = 0;
  for (std::size_t at = chain.output.find("warning"); at != std::string::npos; at = chain.output.find("warning", at + 1))
    ++warnings;
  EXPECT_EQ(warnings, 1u) << chain.output;
  // A budget an offered level has exactly: no warning.
  const CliRun exact = run_cli("extract " + model.string() + " --structure octree --triangles " +
                               std::to_string(over) + " -o " + out);
  ASSERT_EQ(exact.status, 0) << exact.output;
  EXPECT_EQ(exact.output.find("warning"), std::string::npos) << exact.output;
}

// The cluster hierarchy through the command line: the full cut is the
// reconstruction the octree holds too, budgets, errors and cameras give cuts,
// and --json reports clusters and selection time.
TEST(LodCli, ClusterCutsByBudgetErrorAndCamera) {
  const fs::path& model = bunny_model();
  const CliRun info = run_cli("info " + model.string() + " --json", false);
  ASSERT_EQ(info.status, 0) << info.output;
  const nlohmann::json j = nlohmann::json::parse(info.output);
  ASSERT_TRUE(j.contains("clusters")) << info.output;
  const auto& c = j.at("clusters");
  const std::size_t full = c.at("full_triangles").get<std::size_t>();
  EXPECT_EQ(full, j.at("levels_of_detail")[0].at("triangles").get<std::size_t>()) << "both index the same mesh";
  EXPECT_LE(c.at("coarsest_triangles").get<std::size_t>(), 256u);
  EXPECT_LE(c.at("stored_triangles").get<double>(), 2.4 * double(full));

  auto extract = [&](const std::string& args) {
    const CliRun r = run_cli("extract " + model.string() + " " + args + " -o " + (scratch() / "c.ply").string() +
                                 " --json",
                             false);
    EXPECT_EQ(r.status, 0) << args << ": " << r.output;
    return nlohmann::json::parse(r.output);
  };
  const nlohmann::json all = extract("--percent 100");
  EXPECT_EQ(all.at("structure").get<std::string>(), "clusters");
  EXPECT_EQ(all.at("triangles").get<std::size_t>(), full);
  for (const char* key : {"clusters", "select_seconds", "extract_seconds", "error"})
    EXPECT_TRUE(all.contains(key)) << key;
  const nlohmann::json budget = extract("--triangles 2000 --stored-cut");
  EXPECT_LE(budget.at("triangles").get<std::size_t>(), 2000u);
  EXPECT_GT(budget.at("triangles").get<std::size_t>(), 200u);
  EXPECT_FALSE(budget.contains("refined_from"));
  // Without --stored-cut, a count with a finer stored cut near it is refined
  // to it (which cut: CutRefinement.*).
  int refined = 0;
  for (int t : {1500, 2000, 3000, 4500, 7000}) {
    const nlohmann::json r = extract("--triangles " + std::to_string(t));
    if (!r.contains("refined_from")) continue;
    ++refined;
    EXPECT_LE(r.at("triangles").get<int>(), t);
    EXPECT_GE(r.at("triangles").get<int>(), t - 4);
    EXPECT_GT(r.at("refined_from").get<int>(), t);
  }
  EXPECT_GE(refined, 2);
  // The stored cut's error threshold gives the same cut by --error.
  char threshold[32];
  std::snprintf(threshold, sizeof threshold, "%.9g", budget.at("error").get<double>() * (1 + 1e-6));
  const nlohmann::json by_error = extract(std::string("--error ") + threshold);
  EXPECT_EQ(by_error.at("triangles").get<std::size_t>(), budget.at("triangles").get<std::size_t>());
  // Near the model the camera asks for more than far from it.
  const nlohmann::json near = extract("--camera 0,0.1,0.3,0,0.1,0,0,1,0 --pixel-error 1");
  const nlohmann::json far = extract("--camera 0,0.1,30,0,0.1,0,0,1,0 --pixel-error 1");
  EXPECT_GT(near.at("triangles").get<std::size_t>(), far.at("triangles").get<std::size_t>());
  EXPECT_LT(near.at("select_seconds").get<double>(), 0.01);
}

TEST(LodCli, BadInputsFailCleanlyAndWriteNothing) {
  const fs::path& model = bunny_model();
  ASSERT_TRUE(fs::exists(model));
  const fs::path dir = scratch() / "bad";
  fs::create_directories(dir);
  std::vector<char> bytes(fs::file_size(model));
  std::ifstream(model, std::ios::binary).read(bytes.data(), std::streamsize(bytes.size()));
  // A flipped byte in the clusters' records, which every cut reads (a cut
  // read page by page checks only what it reads).
  std::vector<char> damaged = bytes;
  std::uint32_t sections;
  std::memcpy(&sections, bytes.data() + 16, 4);
  std::uint64_t records = 0;
  for (std::uint32_t i = 0; i < sections; ++i)
    if (std::memcmp(bytes.data() + 40 + 48 * i, "CLUS", 4) == 0) std::memcpy(&records, bytes.data() + 40 + 48 * i + 24, 8);
  ASSERT_GT(records, 0u);
  damaged[records + 5] ^= 0x04;
  std::ofstream(dir / "damaged.mco", std::ios::binary).write(damaged.data(), std::streamsize(damaged.size()));
  std::ofstream(dir / "cut.mco", std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() / 3));
  std::ofstream(dir / "mesh.ply") << "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
  const std::size_t files = files_in(dir);
  const std::string out = (dir / "out.ply").string();
  const std::string m = model.string();
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {"extract " + (dir / "absent.mco").string() + " --percent 50 -o " + out, "absent.mco: cannot read the model"},
      {"extract " + (dir / "damaged.mco").string() + " --percent 50 -o " + out, "checksum mismatch in section"},
      {"extract " + (dir / "cut.mco").string() + " --percent 50 -o " + out, "truncated in section"},
      {"extract " + (dir / "mesh.ply").string() + " --percent 50 -o " + out, "not a scan2lod model"},
      {"extract " + m + " --percent 10 --triangles 100 -o " + out, "exactly one of --percent, --triangles, --error, --camera and --priority, got 2"},
      {"extract " + m + " -o " + out, "exactly one of --percent, --triangles, --error, --camera and --priority, got 0"},
      {"extract " + m + " --percent 150 -o " + out, "--percent must be between 0 and 100, got 150"},
      {"extract " + m + " --percent=-1 -o " + out, "--percent must be between 0 and 100"},
      {"extract " + m + " --triangles=-5 -o " + out, "--triangles must not be negative"},
      {"extract " + m + " --priority 99999999 -o " + out, "priority 99999999 is past the octree's"},
      {"extract " + m + " --structure clusters --priority 3 -o " + out, "the cluster hierarchy has no priority numbers"},
      {"extract " + m + " --structure octree --error 0.01 -o " + out, "not by error or camera"},
      {"extract " + m + " --camera 1,2,3 -o " + out, "--camera needs 9 numbers"},
      {"extract " + m + " --camera 0,0,1,0,0,0,0,1,x -o " + out, "'x' is not a number"},
      {"extract " + m + " --error=-1 -o " + out, "--error must be a finite number >= 0"},
      {"extract " + m + " --camera 0,0,1,0,0,0,0,1,0 --fov 200 -o " + out, "--fov must be in (0, 180)"},
      {"extract " + m + " --percent 50 -o " + (dir / "out.xyz").string(), ".xyz"},
      {"extract " + m + " --percent 50 -o " + (dir / "nowhere" / "out.ply").string(), "does not exist"},
      {"info " + (dir / "damaged.mco").string(), "damaged.mco: checksum mismatch"},
      {"info " + (dir / "absent.mco").string(), "absent.mco: cannot read the model"},
      {"build " + kScans + " -o " + (dir / "model.ply").string() + " -r 16", "extension .mco"},
      {"build " + kScans + " -o " + (dir / "nowhere" / "model.mco").string() + " -r 16", "does not exist"},
      {"build " + kScans + " -o " + (dir / "model.mco").string() + " -r 100", "power of two"},
      {"build " + (dir / "absent.conf").string() + " -o " + (dir / "model.mco").string(), "absent.conf"},
  };
  for (const Case& c : cases) {
    const CliRun r = run_cli(c.args + " -q");
    EXPECT_NE(r.status, 0) << c.args;
    EXPECT_NE(r.output.find("scan2lod: error: "), std::string::npos) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << ": " << r.output;
    EXPECT_EQ(r.output.find("Segmentation"), std::string::npos) << r.output;
    EXPECT_EQ(files_in(dir), files) << "a file was left behind by " << c.args;
  }
}
