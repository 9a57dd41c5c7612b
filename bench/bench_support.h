// What both benchmarks (reconstruct_bench.cpp, lod/lod_bench.cpp) share: each
// timed case in a forked child with its own peak memory and a time limit,
// repeated runs and their median, binary dumps to hand points and meshes from
// a child to the parent, and the facts of the run (date, machine, load,
// source revision) that head every report.
//
// Children get the work by fork() without exec, so a benchmark must never run
// OpenMP itself before its last child is done: libgomp's thread pool does not
// survive fork. load_points_in_child() is there for that reason.
#pragma once

#include <scan2lod/core/types.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <type_traits>
#include <vector>

namespace scan2lod::bench {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start);

// The median of v; 0 when v is empty.
double median(std::vector<double> v);

// printf into a std::string.
std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
// v with `digits` decimals ("%.*f").
std::string fixed(double v, int digits);

// ---------------------------------------------------------------------------
// Plain binary dumps for handing points and meshes from children to the parent.

// T is plain numbers: float/int arrays or Eigen's fixed-size vectors, which
// hold just their coefficients but do not count as trivially copyable.
template <typename T>
void write_array(std::ostream& out, const std::vector<T>& v) {
  static_assert(std::is_standard_layout_v<T>);
  const std::uint64_t n = v.size();
  out.write(reinterpret_cast<const char*>(&n), sizeof n);
  out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(n * sizeof(T)));
}

// Leaves *v alone and `in` failed when the stream ends before the count.
template <typename T>
void read_array(std::istream& in, std::vector<T>* v) {
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), sizeof n);
  if (!in) return;
  v->resize(n);
  in.read(reinterpret_cast<char*>(v->data()), std::streamsize(n * sizeof(T)));
}

// All of the points' arrays. Throws InputError when writing or reading fails.
void dump_points(const std::string& path, const OrientedPoints& points);
OrientedPoints undump_points(const std::string& path);

// Positions and triangles only: nothing else enters a measure. The stream
// forms let a caller append its own data after the mesh.
void write_mesh_arrays(std::ostream& out, const TriangleMesh& mesh);
TriangleMesh read_mesh_arrays(std::istream& in);
void dump_mesh(const std::string& path, const TriangleMesh& mesh);
TriangleMesh undump_mesh(const std::string& path);

// ---------------------------------------------------------------------------
// One piece of work in a forked child.

// What a child reports: a few numbers whose meaning the work decides (by
// convention values[0] is its timed seconds where it has one).
using Values = std::array<double, 8>;

struct Outcome {
  enum Status { ok, failed, timed_out, crashed } status = failed;
  Values values{};      // what the work returned; zeros unless ok
  double peak_mib = 0;  // ru_maxrss of the child, also for killed children
  std::string message;  // why it failed, crashed or was killed
};

// Runs `work` in a forked child and waits for it; kills it after `timeout`
// seconds if timeout > 0. An exception thrown by `work` comes back as a
// `failed` outcome with its message. stdout and stderr are flushed first so
// that the child does not print the parent's buffered output again.
Outcome run_in_child(const std::function<Values()>& work, double timeout);

// Runs work(run) in a child for run = 0, 1, ...: `runs` times in all if the
// first run succeeded and its values[0] (seconds) is under `repeat_under`,
// else once. `progress`, if given, is called after each run.
std::vector<Outcome> run_repeated(const std::function<Values(int run)>& work, int runs, double repeat_under,
                                  double timeout,
                                  const std::function<void(int run, const Outcome&)>& progress = {});

// Whether every run is `ok` (false for none).
bool all_ok(const std::vector<Outcome>& runs);
// The median of the runs' values[0] (their seconds).
double median_seconds(const std::vector<Outcome>& runs);
// The largest peak_mib of the runs.
double peak_mib(const std::vector<Outcome>& runs);

// load_oriented_points({input}) in a child (it runs OpenMP), handed back
// through a dump at `dump_path`. Throws std::runtime_error with the child's
// message if loading fails.
OrientedPoints load_points_in_child(const std::string& input, const std::string& dump_path);

// A fresh directory under /tmp named `prefix`.XXXXXX, removed with everything
// in it when this goes out of scope.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& prefix);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

 private:
  std::filesystem::path dir_;
};

// ---------------------------------------------------------------------------
// Facts about the run.

// "1-min 5-min 15-min" load averages from /proc/loadavg.
std::string load_average();

// The report's first line: "2026-11-22 04:59 UTC · x86_64 · nproc 2 · AMD EPYC
// · load average at start …, after the timed cases …" (date: now).
std::string run_header_line(const std::string& load_at_start, const std::string& load_at_end);

// The report's "OpenMP: …" line (OMP_WAIT_POLICY, which bench/run.sh sets),
// ending in a markdown line break.
std::string openmp_line();

// The source tree's commit, and whether it had uncommitted changes, at run
// time (the binary may be older: the run scripts build nothing); "" without git.
std::string source_revision();

// The first of `candidates` (paths relative to the source tree) that exists,
// canonical; "" if none does.
std::string default_path(std::initializer_list<const char*> candidates);

// The bunny scans: the repository's own copy, else the shared one beside the checkout.
std::string default_input();

// The command line as run, "name arg1 arg2 ...".
std::string command_line(const char* name, int argc, char** argv);

// Writes `text` to `path` through a temporary file renamed into place, so an
// interrupted run keeps the old file. Throws InputError when writing fails.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace scan2lod::bench
