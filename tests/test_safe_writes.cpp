// What a user's Ctrl-C, a read-only file, a replaced file's mode and a
// symbolic link do to an output. A signal at any moment, the write included,
// leaves the output as it was or complete, and never a temporary file; a
// user who may not write the output is refused before any work, with the
// system's "Permission denied"; a replaced file keeps its mode; a link is
// written through. Real processes and real files: the scan2lod binary, run
// as root and, through runuser, as the user nobody.
#include "test_support.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using testing::CliRun;
using testing::exit_code;

std::string bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void put_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << bytes;
}

std::set<std::string> entries_of(const fs::path& folder) {
  std::set<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(folder)) names.insert(e.path().filename().string());
  return names;
}

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A folder of this test file's, everyone may write into (for nobody).
fs::path open_folder(const std::string& name) {
  const fs::path dir = testing::scratch_folder("safe_writes") / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::permissions(dir, fs::perms::all);
  return fs::canonical(dir);
}

// --- Signals ----------------------------------------------------------------

// Starts scan2lod ARGS as this process's child, with no shell between that a
// signal could stop at, its output dropped, and the default action for every
// signal sent here (a parent may have left SIGINT ignored).
pid_t start_cli(const std::vector<std::string>& args, const std::vector<std::string>& extra_env) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults, none;
  sigemptyset(&defaults);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&defaults, sig);
  sigemptyset(&none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  std::vector<std::string> argv_text = {SCAN2LOD_CLI};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_text(extra_env);
  for (char** e = environ; *e; ++e) env_text.push_back(*e);
  std::vector<char*> envp;
  for (std::string& e : env_text) envp.push_back(e.data());
  envp.push_back(nullptr);
  pid_t pid = -1;
  const int failed = posix_spawn(&pid, SCAN2LOD_CLI, &actions, &attr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  return failed ? -1 : pid;
}

// Whether `pid` holds a file open directly in `folder`: its output being
// written, under a temporary name or none at all ("FOLDER/#123 (deleted)").
bool writing_into(pid_t pid, const std::string& folder) {
  std::error_code ec;
  const std::string prefix = folder + "/";
  fs::directory_iterator it(fs::path("/proc") / std::to_string(pid) / "fd", ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    std::error_code link_ec;
    const std::string target = fs::read_symlink(it->path(), link_ec).string();
    if (!link_ec && target.compare(0, prefix.size(), prefix) == 0 &&
        target.find('/', prefix.size()) == std::string::npos)
      return true;
  }
  return false;
}

struct Moment {
  int signal;
  bool at_write;       // when the process is seen writing into the output's folder
  double delay;        // seconds after that, or after the start
  bool output_exists;  // a file is already where the output goes
};

struct Outcome {
  int status = 0;
  bool caught_writing = false;
};

Outcome interrupt(const std::vector<std::string>& args, const std::vector<std::string>& env, const Moment& m,
                  const std::string& folder) {
  Outcome o;
  const pid_t pid = start_cli(args, env);
  if (pid < 0) {
    ADD_FAILURE() << "cannot start " << SCAN2LOD_CLI;
    return o;
  }
  const auto start = Clock::now();
  bool reaped = false;
  if (m.at_write) {
    while (!reaped && seconds_since(start) < 60) {
      if (writing_into(pid, folder)) {
        o.caught_writing = true;
        std::this_thread::sleep_for(std::chrono::duration<double>(m.delay));
        break;
      }
      reaped = waitpid(pid, &o.status, WNOHANG) == pid;
      std::this_thread::sleep_for(std::chrono::microseconds(200));  // leave the child the core
    }
  } else {
    std::this_thread::sleep_for(std::chrono::duration<double>(m.delay));
  }
  if (!reaped) {
    kill(pid, m.signal);
    waitpid(pid, &o.status, 0);
  }
  return o;
}

std::string signal_name(int sig) { return sigabbrev_np(sig) ? std::string("SIG") + sigabbrev_np(sig) : "?"; }

// Interrupts ARGS (which write `output`) at `spread` moments across an
// undisturbed run's time and `at_write` moments timed from when the process is
// seen writing the output (0, 1 and 4 ms after). `signals` take turns, and
// every other run finds a file already where the output goes. After each: the
// folder holds the output alone, either as it was or byte for byte the
// undisturbed run's, and the exit status names the signal.
void interrupt_at_moments(const std::vector<std::string>& args, const fs::path& output,
                          const std::vector<int>& signals, int spread, int at_write,
                          const std::vector<std::string>& env = {}) {
  const fs::path folder = output.parent_path();
  const std::string name = output.filename().string();
  fs::create_directories(folder);
  const std::string watched = fs::canonical(folder).string();  // as /proc shows open files
  // The fastest of three undisturbed runs times the moments: one run slowed
  // by a load on the machine spread them past the runs that followed, which
  // then ended before their signals (a failure seen once beside a build).
  double seconds = std::numeric_limits<double>::infinity();
  for (int run = 0; run < 3; ++run) {
    auto start = Clock::now();
    const pid_t pid = start_cli(args, env);
    ASSERT_GT(pid, 0);
    int status = 0;
    waitpid(pid, &status, 0);
    seconds = std::min(seconds, seconds_since(start));
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the undisturbed run failed";
  }
  const std::string complete = bytes_of(output);
  ASSERT_FALSE(complete.empty());
  const std::string previous = "the output of an earlier run\n";

  std::vector<Moment> moments;
  const double write_delays[] = {0, 0.001, 0.004};
  for (int i = 0; i < spread + at_write; ++i) {
    Moment m;
    m.signal = signals[i % signals.size()];
    m.output_exists = i % 2 == 0;
    m.at_write = i >= spread;
    m.delay = m.at_write ? write_delays[(i - spread) / signals.size() % 3] : seconds * (i + 0.5) / spread;
    moments.push_back(m);
  }
  int caught_writing = 0, ended_by_signal = 0;
  for (const Moment& m : moments) {
    fs::remove_all(folder);
    fs::create_directories(folder);
    if (m.output_exists) put_bytes(output, previous);
    const Outcome o = interrupt(args, env, m, watched);
    caught_writing += o.caught_writing;
    const std::string when = signal_name(m.signal) + (m.at_write ? " at the write + " : " at ") +
                             std::to_string(m.delay) + " s" + (m.output_exists ? ", over an earlier file" : "");
    const bool finished = WIFEXITED(o.status) && WEXITSTATUS(o.status) == 0;
    const bool by_signal = WIFSIGNALED(o.status) && WTERMSIG(o.status) == m.signal;
    ended_by_signal += by_signal;
    EXPECT_TRUE(finished || by_signal) << when << ": status " << o.status;
    const std::set<std::string> left = entries_of(folder);
    EXPECT_TRUE(left.empty() || left == std::set<std::string>{name})
        << when << ": left " << ::testing::PrintToString(left);
    if (fs::exists(output)) {
      const std::string now = bytes_of(output);
      EXPECT_TRUE(now == complete || (m.output_exists && !finished && now == previous))
          << when << ": the output is neither as it was nor complete (" << now.size() << " bytes)";
    } else {
      EXPECT_FALSE(m.output_exists) << when << ": the earlier file is gone";
      EXPECT_FALSE(finished) << when;
    }
  }
  // The moments must reach the write stage, or the test proves little.
  EXPECT_GE(caught_writing, at_write / 3) << "of " << at_write << " moments meant for the write";
  EXPECT_GE(ended_by_signal, (spread + at_write) / 2);
}

TEST(SafeWrites, ASignalDuringReconstructLeavesTheOutputAsItWasOrComplete) {
  const fs::path out = testing::scratch_folder("safe_writes") / "signals_reconstruct" / "bunny.ply";
  interrupt_at_moments({"reconstruct", testing::bunny_scans(), "-r", "64", "-o", out.string(), "-q"}, out,
                       {SIGINT, SIGTERM, SIGKILL}, 11, 9);
}

TEST(SafeWrites, ASignalDuringBuildLeavesTheModelAsItWasOrComplete) {
  const fs::path out = testing::scratch_folder("safe_writes") / "signals_build" / "bunny.mco";
  interrupt_at_moments({"build", testing::bunny_scans(), "-r", "64", "-o", out.string(), "-q"}, out,
                       {SIGINT, SIGTERM, SIGKILL}, 11, 9);
}

TEST(SafeWrites, ASignalDuringExportLeavesTheGltfAsItWasOrComplete) {
  const std::string model = testing::bunny_model().string();
  const fs::path out = testing::scratch_folder("safe_writes") / "signals_export" / "bunny.glb";
  interrupt_at_moments({"export", model, "--levels", "100,60,30,10,5", "-o", out.string(), "-q"}, out,
                       {SIGINT, SIGTERM, SIGKILL}, 11, 9);
}

// Where the file system has no anonymous files, the temporary file has a
// name; SIGINT, SIGTERM and SIGHUP remove it before the process ends.
TEST(SafeWrites, WithNamedTemporaryFilesACaughtSignalStillLeavesNothing) {
  const fs::path out = testing::scratch_folder("safe_writes") / "signals_named" / "bunny.ply";
  interrupt_at_moments({"reconstruct", testing::bunny_scans(), "-r", "64", "-o", out.string(), "-q"}, out,
                       {SIGINT, SIGTERM, SIGHUP}, 3, 9, {"SCAN2LOD_TEMP_FILES=named"});
}

// --- Permissions and links --------------------------------------------------

// Why the user nobody cannot run scan2lod here, or "" when it can.
std::string why_not_as_nobody() {
  if (::geteuid() != 0) return "needs root, to run scan2lod as the user nobody through runuser";
  if (std::system("command -v runuser > /dev/null 2>&1") != 0) return "needs runuser (util-linux)";
  const std::string probe = std::string("runuser -u nobody -- ") + SCAN2LOD_CLI + " --version > /dev/null 2>&1";
  if (std::system(probe.c_str()) != 0) return "the user nobody cannot run " + std::string(SCAN2LOD_CLI);
  return "";
}

CliRun run_as_nobody(const std::string& args) {
  return testing::run_shell(std::string("runuser -u nobody -- ") + SCAN2LOD_CLI + " " + args + " 2>&1");
}


struct stat status_of(const fs::path& p) {
  struct stat st {};
  ::lstat(p.c_str(), &st);
  return st;
}

const uid_t kNobody = 65534;

// A mesh output of a few thousand triangles: the 20 % level of the bunny.
std::string extract_to(const fs::path& out) {
  return "extract " + testing::bunny_model().string() + " --percent 20 -q -o " + out.string();
}

TEST(SafeWrites, AReadOnlyOutputIsRefusedAndLeftAsItWas) {
  const std::string why = why_not_as_nobody();
  if (!why.empty()) GTEST_SKIP() << why;
  const fs::path dir = open_folder("read_only");  // world-writable, as in /tmp without the sticky bit
  // Another user's file, and nobody's own, both mode 444.
  const fs::path theirs = dir / "theirs.ply", own = dir / "own.ply";
  put_bytes(theirs, "root's\n");
  put_bytes(own, "nobody's\n");
  ASSERT_EQ(::chown(own.c_str(), kNobody, kNobody), 0);
  for (const fs::path& p : {theirs, own}) ::chmod(p.c_str(), 0444);
  for (const fs::path& p : {theirs, own}) {
    const struct stat before = status_of(p);
    const std::string bytes = bytes_of(p);
    const CliRun r = run_as_nobody(extract_to(p));
    EXPECT_EQ(exit_code(r), 1) << r.output;
    EXPECT_NE(r.output.find(p.string() + ": cannot write: Permission denied"), std::string::npos) << r.output;
    const struct stat after = status_of(p);
    EXPECT_TRUE(bytes_of(p) == bytes) << p << " was written";
    EXPECT_EQ(after.st_ino, before.st_ino);
    EXPECT_EQ(after.st_uid, before.st_uid);
    EXPECT_EQ(after.st_mode, before.st_mode);
  }
  EXPECT_EQ(entries_of(dir), (std::set<std::string>{"theirs.ply", "own.ply"}));

  // In a sticky folder (/tmp), another user's file is writable but not
  // replaceable: refused, rather than failing after the work.
  const fs::path sticky = open_folder("sticky");
  ::chmod(sticky.c_str(), 01777);
  const fs::path shared = sticky / "shared.ply";
  put_bytes(shared, "root's, writable by all\n");
  ::chmod(shared.c_str(), 0666);
  const CliRun r = run_as_nobody(extract_to(shared));
  EXPECT_EQ(exit_code(r), 1) << r.output;
  EXPECT_NE(r.output.find("sticky"), std::string::npos) << r.output;
  EXPECT_TRUE(bytes_of(shared) == "root's, writable by all\n") << shared << " was written";
  EXPECT_EQ(entries_of(sticky), std::set<std::string>{"shared.ply"});
}

TEST(SafeWrites, AReplacedFileKeepsItsMode) {
  const std::string why = why_not_as_nobody();
  if (!why.empty()) GTEST_SKIP() << why;
  const fs::path dir = open_folder("modes");
  for (const mode_t mode : {0600, 0640, 0664, 0604}) {
    const fs::path p = dir / ("mode" + std::to_string(mode) + ".ply");
    put_bytes(p, "old\n");
    ASSERT_EQ(::chown(p.c_str(), kNobody, kNobody), 0);
    ::chmod(p.c_str(), mode);
    const CliRun r = run_as_nobody(extract_to(p));
    EXPECT_EQ(exit_code(r), 0) << r.output;
    const struct stat st = status_of(p);
    EXPECT_EQ(st.st_mode & 07777, mode) << p;
    EXPECT_EQ(st.st_uid, kNobody) << p;
    EXPECT_GT(st.st_size, 1000) << p;
  }
  // Root replacing a user's file keeps its owner, group and mode too.
  const fs::path users = dir / "users.ply";
  put_bytes(users, "old\n");
  ASSERT_EQ(::chown(users.c_str(), kNobody, kNobody), 0);
  ::chmod(users.c_str(), 0600);
  const CliRun r = testing::run_cli(extract_to(users));
  EXPECT_EQ(exit_code(r), 0) << r.output;
  const struct stat st = status_of(users);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  EXPECT_EQ(st.st_uid, kNobody);
  EXPECT_EQ(st.st_gid, gid_t(kNobody));
  EXPECT_GT(st.st_size, 1000);
  // A new file gets the mode the umask leaves, as any program's would.
  const fs::path fresh = dir / "fresh.ply", probe = dir / "probe";
  ASSERT_EQ(std::system(("runuser -u nobody -- touch " + probe.string()).c_str()), 0);
  const CliRun n = run_as_nobody(extract_to(fresh));
  EXPECT_EQ(exit_code(n), 0) << n.output;
  EXPECT_EQ(status_of(fresh).st_mode & 07777, status_of(probe).st_mode & 07777);
}

TEST(SafeWrites, AnOutputThroughASymbolicLinkWritesTheLinksTarget) {
  const std::string why = why_not_as_nobody();
  if (!why.empty()) GTEST_SKIP() << why;
  const fs::path dir = open_folder("links");
  const fs::path real = dir / "real";
  fs::create_directories(real);
  fs::permissions(real, fs::perms::all);
  // A chain: chain.ply -> link.ply -> real/target.ply (relative), and an
  // absolute link; each written through, the links left as they were.
  const fs::path target = real / "target.ply";
  put_bytes(target, "old\n");
  ASSERT_EQ(::chown(target.c_str(), kNobody, kNobody), 0);
  ::chmod(target.c_str(), 0640);
  fs::create_symlink("real/target.ply", dir / "link.ply");
  fs::create_symlink("link.ply", dir / "chain.ply");
  fs::create_symlink(target, dir / "absolute.ply");
  for (const std::string link : {"chain.ply", "link.ply", "absolute.ply"}) {
    put_bytes(target, "old\n");
    const CliRun r = run_as_nobody(extract_to(dir / link));
    EXPECT_EQ(exit_code(r), 0) << link << ": " << r.output;
    EXPECT_TRUE(fs::is_symlink(dir / link)) << link << " was replaced by a file";
    EXPECT_GT(fs::file_size(target), 1000u) << link;
    EXPECT_EQ(status_of(target).st_mode & 07777, 0640u) << link;
  }
  EXPECT_EQ(fs::read_symlink(dir / "chain.ply"), fs::path("link.ply"));
  EXPECT_EQ(entries_of(dir), (std::set<std::string>{"real", "link.ply", "chain.ply", "absolute.ply"}));
  EXPECT_EQ(entries_of(real), std::set<std::string>{"target.ply"});
  // A link to a file not there yet creates it, as a shell's `>` would.
  fs::create_symlink("real/new.ply", dir / "dangling.ply");
  const CliRun r = run_as_nobody(extract_to(dir / "dangling.ply"));
  EXPECT_EQ(exit_code(r), 0) << r.output;
  EXPECT_TRUE(fs::is_symlink(dir / "dangling.ply"));
  EXPECT_GT(fs::file_size(real / "new.ply"), 1000u);
  // A link to a read-only file is refused like the file.
  ::chmod(target.c_str(), 0440);
  const std::string before = bytes_of(target);
  const CliRun ro = run_as_nobody(extract_to(dir / "chain.ply"));
  EXPECT_EQ(exit_code(ro), 1) << ro.output;
  EXPECT_NE(ro.output.find("Permission denied"), std::string::npos) << ro.output;
  EXPECT_TRUE(bytes_of(target) == before) << target << " was written";
}

TEST(SafeWrites, EveryCommandRefusesAnUnwritableFolderBeforeItStarts) {
  const std::string why = why_not_as_nobody();
  if (!why.empty()) GTEST_SKIP() << why;
  const fs::path dir = open_folder("unwritable");
  const fs::path locked = dir / "locked";
  fs::create_directories(locked);
  ::chmod(locked.c_str(), 0555);
  const std::string model = testing::bunny_model().string();
  const std::string scans = testing::bunny_scans();
  const fs::path mesh = dir / "mesh.ply";
  ASSERT_EQ(exit_code(testing::run_cli(extract_to(mesh))), 0);
  const std::string out = locked.string() + "/";
  // R = 512: minutes of work for a command that only found out at the end.
  const std::vector<std::string> commands = {
      "reconstruct " + scans + " -r 512 -o " + out + "bunny.ply",
      "build " + scans + " -r 512 -o " + out + "bunny.mco",
      "extract " + model + " --percent 20 -o " + out + "level.ply",
      "export " + model + " --levels 50,10 -o " + out + "levels.glb",
      "export " + model + " --levels 50,10 -o " + out + "level.ply",
      "render " + model + " -o " + out + "montage.png",
      "plot " + model + " -o " + out + "plot.png",
      "convert " + scans + " -o " + out + "scans",
      "scan " + mesh.string() + " -o " + out + "scans",
      "view " + model + " --script /dev/null --screenshot " + out + "shot.png",
  };
  for (const std::string& command : commands) {
    const auto start = Clock::now();
    const CliRun r = run_as_nobody(command);
    const double seconds = seconds_since(start);
    EXPECT_EQ(exit_code(r), 1) << command << ": " << r.output;
    EXPECT_NE(r.output.find("cannot write into folder " + locked.string() + ": Permission denied"),
              std::string::npos)
        << command << ": " << r.output;
    EXPECT_EQ(r.output.find("disk space"), std::string::npos) << command << ": " << r.output;
    EXPECT_LT(seconds, 3.0) << command << ": refused only after its work";
  }
  EXPECT_TRUE(fs::is_empty(locked));
}

}  // namespace
}  // namespace scan2lod
