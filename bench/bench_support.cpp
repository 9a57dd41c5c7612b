#include <scan2lod/bench/bench_support.h>

#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/core/error.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <stdexcept>
#include <thread>

namespace fs = std::filesystem;

namespace scan2lod::bench {

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string format(const char* fmt, ...) {
  va_list args;
  va_start(args, fmt);
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, fmt, copy);
  va_end(copy);
  std::string out(std::size_t(std::max(n, 0)), '\0');
  std::vsnprintf(out.data(), out.size() + 1, fmt, args);
  va_end(args);
  return out;
}

std::string fixed(double v, int digits) { return format("%.*f", digits, v); }

// ---------------------------------------------------------------------------
// Dumps.

void dump_points(const std::string& path, const OrientedPoints& p) {
  std::ofstream out(path, std::ios::binary);
  write_array(out, p.positions);
  write_array(out, p.normals);
  write_array(out, p.colors);
  write_array(out, p.confidence);
  write_array(out, p.spacing);
  if (!out) throw InputError(path, "could not write the points dump");
}

OrientedPoints undump_points(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  OrientedPoints p;
  read_array(in, &p.positions);
  read_array(in, &p.normals);
  read_array(in, &p.colors);
  read_array(in, &p.confidence);
  read_array(in, &p.spacing);
  if (!in) throw InputError(path, "truncated points dump");
  return p;
}

void write_mesh_arrays(std::ostream& out, const TriangleMesh& m) {
  write_array(out, m.positions);
  write_array(out, m.triangles);
}

TriangleMesh read_mesh_arrays(std::istream& in) {
  TriangleMesh m;
  read_array(in, &m.positions);
  read_array(in, &m.triangles);
  return m;
}

void dump_mesh(const std::string& path, const TriangleMesh& m) {
  std::ofstream out(path, std::ios::binary);
  write_mesh_arrays(out, m);
  if (!out) throw InputError(path, "could not write the mesh dump");
}

TriangleMesh undump_mesh(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  TriangleMesh m = read_mesh_arrays(in);
  if (!in) throw InputError(path, "truncated mesh dump");
  return m;
}

// ---------------------------------------------------------------------------
// Children.

namespace {

// Fixed size and below PIPE_BUF, so one write() and no blocking before the read.
struct ChildMessage {
  Values values{};
  int ok = 0;
  char error[1024] = {};
};
static_assert(sizeof(ChildMessage) <= PIPE_BUF);

}  // namespace

Outcome run_in_child(const std::function<Values()>& work, double timeout) {
  std::fflush(stdout);
  std::fflush(stderr);
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe() failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork() failed");
  if (pid == 0) {
    close(fds[0]);
    ChildMessage msg;
    try {
      msg.values = work();
      msg.ok = 1;
    } catch (const std::exception& e) {
      std::snprintf(msg.error, sizeof msg.error, "%s", e.what());
    }
    [[maybe_unused]] const ssize_t written = write(fds[1], &msg, sizeof msg);
    _exit(0);  // no atexit handlers or static destructors of the parent's state
  }
  close(fds[1]);

  const auto start = Clock::now();
  int status = 0;
  rusage usage{};
  bool killed = false;
  for (;;) {
    const pid_t done = wait4(pid, &status, killed ? 0 : WNOHANG, &usage);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) throw std::runtime_error("wait4() failed");
    if (!killed && timeout > 0 && seconds_since(start) > timeout) {
      kill(pid, SIGKILL);
      killed = true;
      continue;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }

  Outcome out;
  out.peak_mib = double(usage.ru_maxrss) / 1024.0;  // KiB on Linux
  ChildMessage msg;
  const ssize_t got = read(fds[0], &msg, sizeof msg);
  close(fds[0]);
  if (killed) {
    out.status = Outcome::timed_out;
    out.message = "killed at the " + std::to_string(int(timeout)) + " s timeout";
  } else if (WIFSIGNALED(status)) {
    out.status = Outcome::crashed;
    out.message = std::string("crashed: ") + strsignal(WTERMSIG(status));
  } else if (got != ssize_t(sizeof msg) || !msg.ok) {
    out.status = Outcome::failed;
    out.message = got == ssize_t(sizeof msg) ? msg.error : "exited without a result";
  } else {
    out.status = Outcome::ok;
    out.values = msg.values;
  }
  return out;
}

std::vector<Outcome> run_repeated(const std::function<Values(int run)>& work, int runs, double repeat_under,
                                  double timeout, const std::function<void(int run, const Outcome&)>& progress) {
  std::vector<Outcome> out;
  for (int run = 0; run < runs; ++run) {
    if (run == 1 && !(out[0].status == Outcome::ok && out[0].values[0] < repeat_under)) break;
    out.push_back(run_in_child([&] { return work(run); }, timeout));
    if (progress) progress(run, out.back());
  }
  return out;
}

bool all_ok(const std::vector<Outcome>& runs) {
  return !runs.empty() &&
         std::all_of(runs.begin(), runs.end(), [](const Outcome& o) { return o.status == Outcome::ok; });
}

double median_seconds(const std::vector<Outcome>& runs) {
  std::vector<double> s;
  for (const Outcome& o : runs) s.push_back(o.values[0]);
  return median(s);
}

double peak_mib(const std::vector<Outcome>& runs) {
  double m = 0;
  for (const Outcome& o : runs) m = std::max(m, o.peak_mib);
  return m;
}

OrientedPoints load_points_in_child(const std::string& input, const std::string& dump_path) {
  const Outcome loaded = run_in_child([&] {
    const auto start = Clock::now();
    dump_points(dump_path, load_oriented_points({input}));
    return Values{seconds_since(start)};
  }, 0);
  if (loaded.status != Outcome::ok) throw std::runtime_error(loaded.message);
  return undump_points(dump_path);
}

ScratchDir::ScratchDir(const std::string& prefix) {
  std::string name = "/tmp/" + prefix + ".XXXXXX";
  if (!mkdtemp(name.data())) throw std::runtime_error("mkdtemp(" + name + "): " + std::strerror(errno));
  dir_ = name;
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  fs::remove_all(dir_, ec);
}

// ---------------------------------------------------------------------------
// Facts about the run.

namespace {

std::string cpu_model() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos) return line.substr(line.find(':') + 2);
  return {};
}

}  // namespace

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

std::string run_header_line(const std::string& load_at_start, const std::string& load_at_end) {
  utsname u{};
  uname(&u);
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  const std::string cpu = cpu_model();
  return format("%s · %s · nproc %ld%s%s · load average at start %s, after the timed cases %s", date, u.machine,
                sysconf(_SC_NPROCESSORS_ONLN), cpu.empty() ? "" : " · ", cpu.c_str(), load_at_start.c_str(),
                load_at_end.c_str());
}

std::string openmp_line() {
  if (const char* policy = std::getenv("OMP_WAIT_POLICY")) return format("OpenMP: `OMP_WAIT_POLICY=%s`  \n", policy);
  return "OpenMP: `OMP_WAIT_POLICY` unset (libgomp's default: spin, then sleep)  \n";
}

std::string source_revision() {
  const auto run = [](const std::string& command) {
    std::string out;
    if (FILE* f = popen(command.c_str(), "r")) {
      char buf[256];
      while (std::fgets(buf, sizeof buf, f)) out += buf;
      pclose(f);
    }
    return out;
  };
  const std::string git = "git -C '" + std::string(SCAN2LOD_SOURCE_DIR) + "' ";
  std::string head = run(git + "rev-parse --short HEAD 2>/dev/null");
  if (head.empty()) return {};
  head.pop_back();  // newline
  const bool dirty = !run(git + "status --porcelain --untracked-files=no 2>/dev/null").empty();
  return head + (dirty ? " with uncommitted changes" : "");
}

std::string default_path(std::initializer_list<const char*> candidates) {
  for (const char* c : candidates) {
    const fs::path p = fs::path(SCAN2LOD_SOURCE_DIR) / c;
    if (fs::exists(p)) return fs::weakly_canonical(p).string();
  }
  return {};
}

std::string default_input() {
  return default_path({"data/bunny/bun.conf", "../shared/data/bunny/data/bun.conf"});
}

std::string command_line(const char* name, int argc, char** argv) {
  std::string line = name;
  for (int i = 1; i < argc; ++i) line += std::string(" ") + argv[i];
  return line;
}

void write_file_atomically(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    if (!out) throw InputError(tmp.string(), "could not write");
  }
  fs::rename(tmp, path);
}

}  // namespace scan2lod::bench
