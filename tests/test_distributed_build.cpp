// The brick build shared among MPI ranks (`mpirun -np N scan2lod build`) writes
// the single process's model byte for byte, for 2 ranks and for 3 ranks on
// fewer cores, whether rank 0 bins the points every rank read or each rank
// bins its own share; and a job one of whose ranks is killed half way
// resumes from the bricks it finished, again to the same bytes. Registered
// only when scan2lod was built with MPI.
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#ifdef SCAN2LOD_MPIEXEC

extern char** environ;

namespace fs = std::filesystem;
using scan2lod::testing::CliRun;
using scan2lod::testing::run_shell;

namespace {

// The bunny's scans at a resolution and budget that cut them into at least
// 8 bricks (checked below), quick enough for several builds in a test.
const std::string kBuild = " --structure clusters -r 256 --memory 100M -q --json";
// The same in bricks of 64 cubes, which sends the points by bricks whatever
// their size: each rank bins the share of the scans it read.
const std::string kShares = " --brick-cubes 64";

// `mpirun` for `ranks` ranks on this machine: more ranks than cores, and as
// root (CI containers) too.
std::string launcher(int ranks) {
  return "env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + std::string(SCAN2LOD_MPIEXEC) +
         " --oversubscribe -np " + std::to_string(ranks) + " ";
}

// `scan2lod build` of the bunny into dir/name.mco (work folder dir/name.work),
// alone (ranks 0) or under mpirun, with kBuild and `more`.
std::string build_command(int ranks, const fs::path& dir, const std::string& name, const std::string& more = "") {
  return (ranks > 0 ? launcher(ranks) : std::string()) + SCAN2LOD_CLI + " build " +
         scan2lod::testing::bunny_scans() + kBuild + more + " --work-dir " + (dir / (name + ".work")).string() +
         " -o " + (dir / (name + ".mco")).string();
}

std::string bytes_of(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// The JSON object a run printed (the launcher may print around it).
nlohmann::json json_of(const CliRun& r) {
  const std::size_t start = r.output.find('{'), end = r.output.rfind('}');
  if (start == std::string::npos || end == std::string::npos || end < start) return nlohmann::json::value_t::discarded;
  return nlohmann::json::parse(r.output.substr(start, end + 1 - start), nullptr, false);
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = scan2lod::testing::scratch_folder("distributed") / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

struct Alone {
  std::string bytes;    // of the model
  std::int64_t points;  // read
};

Alone single_process_model_with(const std::string& more, const std::string& name) {
  const fs::path dir = fresh_dir(name);
  const CliRun r = run_shell(build_command(0, dir, name, more) + " 2>&1");
  EXPECT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = json_of(r);
  EXPECT_GE(j.value("/bricks/bricks"_json_pointer, 0), 8) << r.output;
  return {bytes_of(dir / (name + ".mco")), j.value("points", std::int64_t(0))};
}

// The single process's models, each built once per test process.
const std::string& single_process_model() {
  static const Alone alone = single_process_model_with("", "alone");
  return alone.bytes;
}
const Alone& single_process_model_in_shares() {
  static const Alone alone = single_process_model_with(kShares, "alone_shares");
  return alone;
}

// The pid of the rank `rank` of the job writing to `work_dir`, or 0.
pid_t rank_pid(int rank, const std::string& work_dir) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string command = bytes_of(entry.path() / "cmdline"), environment = bytes_of(entry.path() / "environ");
    if (command.find(work_dir) == std::string::npos) continue;  // the launcher has no rank below
    const std::string wanted = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
    for (std::size_t at = 0; at < environment.size();) {
      const std::size_t end = std::min(environment.find('\0', at), environment.size());
      if (environment.compare(at, end - at, wanted) == 0) return pid_t(std::stol(name));
      at = end + 1;
    }
  }
  return 0;
}

std::size_t finished_bricks(const fs::path& dir) {
  std::size_t n = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) n += entry.path().extension() == ".brick";
  return n;
}

}  // namespace

TEST(DistributedBuild, TwoRanksWriteTheSingleProcessModel) {
  const std::string& alone = single_process_model();
  ASSERT_FALSE(alone.empty());
  const fs::path dir = fresh_dir("two");
  const CliRun r = run_shell(build_command(2, dir, "two") + " 2>&1");
  ASSERT_EQ(r.status, 0) << r.output;
  // Rank 0 alone speaks: one JSON object, the same bricks as alone.
  const nlohmann::json j = json_of(r);
  ASSERT_FALSE(j.is_discarded()) << r.output;
  EXPECT_GE(j.value("/bricks/bricks"_json_pointer, 0), 8);
  EXPECT_EQ(j.value("/bricks/resumed"_json_pointer, -1), 0);
  EXPECT_TRUE(bytes_of(dir / "two.mco") == alone);
}

TEST(DistributedBuild, ThreeRanksOnFewerCoresWriteTheSingleProcessModel) {
  const std::string& alone = single_process_model();
  ASSERT_FALSE(alone.empty());
  const fs::path dir = fresh_dir("three");
  const CliRun r = run_shell(build_command(3, dir, "three") + " 2>&1");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(bytes_of(dir / "three.mco") == alone);
}

TEST(DistributedBuild, RanksThatBinTheirOwnSharesWriteTheSingleProcessModel) {
  const Alone& alone = single_process_model_in_shares();
  ASSERT_FALSE(alone.bytes.empty());
  for (int ranks : {2, 3}) {
    const fs::path dir = fresh_dir("shares" + std::to_string(ranks));
    const CliRun r = run_shell(build_command(ranks, dir, "shares", kShares) + " 2>&1");
    ASSERT_EQ(r.status, 0) << r.output;
    const nlohmann::json j = json_of(r);
    ASSERT_FALSE(j.is_discarded()) << r.output;
    // Rank 0 counts every rank's points.
    EXPECT_EQ(j.value("points", std::int64_t(0)), alone.points) << r.output;
    EXPECT_TRUE(bytes_of(dir / "shares.mco") == alone.bytes) << ranks << " ranks";
    // Each rank's spool and bins are gone with the job.
    std::size_t left = 0;
    for (const auto& entry : fs::directory_iterator(dir / "shares.work"))
      left += entry.path().extension() == ".spool" || entry.path().extension() == ".bins";
    EXPECT_EQ(left, 0u);
  }
}

TEST(DistributedBuild, RanksThatMakeTheHierarchysBlocksWriteTheSingleProcessModel) {
  // Blocks of 16 k triangles: the bunny's hierarchy in about 10 blocks at
  // first, each pass's blocks made on every rank and committed everywhere.
  const std::string blocks = " --cluster-block 16384";
  const Alone& alone = single_process_model_with(blocks, "alone_blocks");
  ASSERT_FALSE(alone.bytes.empty());
  for (int ranks : {2, 3}) {
    const std::string name = "blocks" + std::to_string(ranks);
    const fs::path dir = fresh_dir(name);
    const CliRun r = run_shell(build_command(ranks, dir, name, blocks) + " 2>&1");
    ASSERT_EQ(r.status, 0) << r.output;
    const nlohmann::json j = json_of(r);
    ASSERT_FALSE(j.is_discarded()) << r.output;
    const std::size_t made = j.value("/cluster_blocks/made"_json_pointer, std::size_t(0));
    const std::size_t here = j.value("/cluster_blocks/here"_json_pointer, made);
    EXPECT_GE(made, 8u) << r.output;
    // Rank 0 made its share of each pass (block b is rank b mod N's), not all of them.
    EXPECT_GE(here, made / std::size_t(ranks)) << r.output;
    EXPECT_LE(here, made / std::size_t(ranks) + 8) << r.output;
    EXPECT_GT(j.value("/cluster_blocks/exchanged_mib"_json_pointer, 0.0), 1.0) << r.output;
    EXPECT_TRUE(bytes_of(dir / (name + ".mco")) == alone.bytes) << ranks << " ranks";
  }
}

TEST(DistributedBuild, AJobWithAKilledRankResumesToTheSameModel) {
  // The ranks bin their own shares: the path of inputs larger than memory.
  const std::string& alone = single_process_model_in_shares().bytes;
  ASSERT_FALSE(alone.empty());
  const fs::path dir = fresh_dir("killed");
  const std::string work = (dir / "killed.work").string();
  // The launcher itself is the child (exec), so that its end can be waited for.
  const std::string command = "exec " + build_command(2, dir, "killed", kShares) + " >/dev/null 2>&1";
  const char* argv[] = {"sh", "-c", command.c_str(), nullptr};
  pid_t job = 0;
  ASSERT_EQ(posix_spawn(&job, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ), 0);
  // Rank 1 is killed (SIGKILL: nothing of it runs on) once bricks are being
  // finished; the launcher then ends the job.
  pid_t victim = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  int status = 0;
  while (std::chrono::steady_clock::now() < deadline && ::waitpid(job, &status, WNOHANG) == 0) {
    if (finished_bricks(fs::path(work) / "bricks") >= 2 && (victim = rank_pid(1, work)) > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_GT(victim, 0) << "the job ended before a rank could be killed";
  ::kill(victim, SIGKILL);
  ASSERT_EQ(::waitpid(job, &status, 0), job);
  EXPECT_NE(status, 0);
  EXPECT_FALSE(fs::exists(dir / "killed.mco"));

  // The same command again: the finished bricks are taken as they are.
  const CliRun r = run_shell(build_command(2, dir, "killed", kShares) + " 2>&1");
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = json_of(r);
  EXPECT_GE(j.value("/bricks/resumed"_json_pointer, 0), 2) << r.output;
  EXPECT_TRUE(bytes_of(dir / "killed.mco") == alone);
}

TEST(DistributedBuild, AnErrorOnAnyRankEndsTheJobWithItsMessage) {
  // The input cannot be read: the job ends (no rank waits forever), with
  // the message, the rank that met it, and a failing exit code.
  const fs::path dir = fresh_dir("error");
  const CliRun r = run_shell(launcher(2) + SCAN2LOD_CLI + " build " + (dir / "missing.conf").string() + kBuild +
                             " -o " + (dir / "m.mco").string() + " 2>&1");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("missing.conf"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" of 2"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "m.mco"));
  // Rank 1 started with other options refuses rank 0's plan: the same.
  const std::string rank = std::string(SCAN2LOD_CLI) + " build " + scan2lod::testing::bunny_scans() + kBuild +
                           " --work-dir " + (dir / "w").string() + " -o " + (dir / "m.mco").string();
  const CliRun other = run_shell(launcher(1) + rank + " : -np 1 " + rank + " --neighbours 9 2>&1");
  EXPECT_NE(other.status, 0);
  EXPECT_NE(other.output.find("rank 1 of 2"), std::string::npos) << other.output;
  EXPECT_NE(other.output.find("other reconstruction options"), std::string::npos) << other.output;
  EXPECT_FALSE(fs::exists(dir / "m.mco"));
}

#endif  // SCAN2LOD_MPIEXEC
