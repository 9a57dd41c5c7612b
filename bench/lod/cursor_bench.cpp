// Incremental extraction benchmark: LodCursor::move_to (lod/octree/lod_cursor.h)
// against extract_lod from scratch at the same target, for the moves a slider
// makes, on the same model in the same run. What is reported is the ratio.
//
// Moves, with levels taken as the viewer's slider takes them
// (priority_for_percent):
//   ±1 % and ±5 %: from every 5 % start (5, 10, ... %) one step up, or down
//   onto it; the cursor is put at the start untimed, then the move is timed.
//   Sweep: 1 % to 100 % in 1 % steps, each step timed.
//   Jump: 1 % to 100 %, and back, in one move (all of the array at once).
// Each case runs --reps times; every timed move is followed by extract_lod at
// its target, timed with its scratch reused, on one thread and on all cores
// (extract_lod splits levels from 1,024 expansions on across cores; the cursor
// runs on one). Ratios are extract_lod's median over move_to's, and the total
// of each over all moves (which counts the cursor's occasional compaction).
// Before every timed call the caches are flushed (64 MiB written and read, as
// a viewer's rendering between moves would), unless --warm: otherwise the
// second call would find the target level's nodes in cache from the first.
//
// No forked children, unlike lod_bench.cpp: nothing is measured for memory,
// and building the model in this process before the timing is harmless.
//
// Output: a markdown report on stdout; progress on stderr.
//
//   build/bin/scan2lod_bench_cursor [--model MODEL.mco | --input SCANS --resolution R]
//                                   [--reps N] [--only TEXT] [--warm]

#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/bench/bench_support.h>
#include <scan2lod/bench/model_build.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/lod_cursor.h>

#include <CLI/CLI.hpp>
#include <omp.h>

#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

using namespace scan2lod;
using namespace scan2lod::bench;

namespace {

struct MoveCase {
  std::string name;
  std::vector<std::pair<double, double>> moves;  // (from, to) in percent
  bool chained = false;  // each move starts where the last ended: no untimed positioning
};

std::vector<MoveCase> make_cases() {
  std::vector<MoveCase> cases;
  for (const double step : {1.0, 5.0}) {
    MoveCase up{"+" + fixed(step, 0) + " %", {}, false}, down{"−" + fixed(step, 0) + " %", {}, false};
    for (double start = 5; start + step <= 100; start += 5) {
      up.moves.push_back({start, start + step});
      down.moves.push_back({start + step, start});
    }
    cases.push_back(std::move(up));
    cases.push_back(std::move(down));
  }
  MoveCase sweep{"sweep 1 → 100 % in 1 % steps", {}, true};
  for (int p = 1; p < 100; ++p) sweep.moves.push_back({p, p + 1});
  cases.push_back(std::move(sweep));
  cases.push_back({"jump 1 → 100 %", {{1, 100}}, false});
  cases.push_back({"jump 100 → 1 %", {{100, 1}}, false});
  return cases;
}

struct CaseResult {
  std::vector<double> move, extract_one, extract_all;  // seconds per timed move
  double expansions = 0, emitted = 0, triangles = 0, rebuilt = 0;  // sums over the timed moves
};

double sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

// Evicts the model from the caches (the largest L3 here is 32 MiB).
void flush_caches() {
  static std::vector<std::uint64_t> junk(std::size_t(64) << 17);
  static volatile std::uint64_t sink = 0;
  std::uint64_t total = 0;
  for (std::uint64_t& x : junk) total += ++x;
  sink = sink + total;
}

// The octree alone: the cursor is the octree's, and extract_lod is what it is
// measured against (lod/lod_model.h's LevelExtractor calls it for the octree).
double timed_extract(const OctreeLod& m, std::size_t priority, int threads, bool cold,
                     std::vector<std::uint8_t>* scratch, std::vector<Triangle>* triangles) {
  omp_set_num_threads(threads);
  if (cold) flush_caches();
  const auto start = Clock::now();
  extract_lod(m.tree, m.lod, priority, scratch, triangles);
  return seconds_since(start);
}

CaseResult run_case(const OctreeLod& m, const MoveCase& c, int reps, int all_threads, bool cold) {
  CaseResult r;
  LodCursor cursor(m.tree, m.lod);
  std::vector<std::uint8_t> scratch;
  std::vector<Triangle> triangles;
  extract_lod(m.tree, m.lod, m.lod.full(), &scratch, &triangles);  // sizes the scratch
  for (int rep = 0; rep < reps; ++rep) {
    if (c.chained) cursor.move_to(priority_for_percent(m.lod, c.moves.front().first));
    for (const auto& [from_percent, to_percent] : c.moves) {
      const std::size_t from = priority_for_percent(m.lod, from_percent), to = priority_for_percent(m.lod, to_percent);
      if (!c.chained) cursor.move_to(from);
      if (cold) flush_caches();
      const auto start = Clock::now();
      cursor.move_to(to);
      r.move.push_back(seconds_since(start));
      if (cursor.triangles() != m.lod.accumulated[to])
        throw std::runtime_error("the cursor's count at priority " + std::to_string(to) + " is not the table's");
      r.expansions += double(from > to ? from - to : to - from);
      r.emitted += double(cursor.emitted_nodes_last_move());
      r.rebuilt += cursor.rebuilt_last_move();
      r.triangles += double(cursor.triangles());
      r.extract_one.push_back(timed_extract(m, to, 1, cold, &scratch, &triangles));
      r.extract_all.push_back(timed_extract(m, to, all_threads, cold, &scratch, &triangles));
    }
  }
  omp_set_num_threads(all_threads);
  return r;
}

std::string us(double seconds) { return fixed(seconds * 1e6, seconds < 1e-4 ? 1 : 0); }
std::string ratio(double r) { return fixed(r, r < 10 ? 2 : 0) + "×"; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Times LodCursor::move_to against extract_lod from scratch for slider-like moves; prints a "
               "markdown report of their ratios"};
  std::string input = default_input(), model_path;
  std::string only;
  int resolution = 256, reps = 5;
  app.add_option("--input", input, "Scans to build the model from, as `scan2lod build` (default: the bunny)");
  app.add_option("--model", model_path, "A .mco model to load instead of building one");
  app.add_option("--resolution", resolution, "Leaf cubes per side when building (a power of two)");
  app.add_option("--reps", reps, "Runs of every case")->check(CLI::PositiveNumber);
  app.add_option("--only", only, "Run only the cases whose name contains this");
  bool warm = false;
  app.add_flag("--warm", warm, "Do not flush the caches before each timed call");
  CLI11_PARSE(app, argc, argv);
  Progress::set_quiet(true);
  const std::string load_at_start = load_average();

  LodModel model;
  std::string source;
  if (!model_path.empty()) {
    std::fprintf(stderr, "loading %s\n", model_path.c_str());
    model = load_model(model_path);
    source = "model `" + model_path + "`";
  } else {
    if (input.empty()) {
      std::fprintf(stderr, "no input: neither the bundled nor the shared bunny exists; pass --input or --model\n");
      return 2;
    }
    std::fprintf(stderr, "building the model of %s at R=%d\n", input.c_str(), resolution);
    model = build_model_timed(load_oriented_points({input}), resolution, /*clusters=*/false).model;
    source = "`" + input + "` built at R = " + std::to_string(resolution) + " (bench/model_build.h)";
  }
  if (!model.octree) {
    std::fprintf(stderr, "%s has no octree: build it with scan2lod build --structure octree or both\n",
                 source.c_str());
    return 2;
  }
  const OctreeLod& octree = *model.octree;
  const int threads = omp_get_max_threads();

  std::vector<std::pair<const MoveCase*, CaseResult>> results;
  const std::vector<MoveCase> cases = make_cases();
  for (const MoveCase& c : cases) {
    if (c.name.find(only) == std::string::npos) continue;
    std::fprintf(stderr, "%s\n", c.name.c_str());
    results.push_back({&c, run_case(octree, c, reps, threads, !warm)});
  }

  std::printf("# Incremental extraction: `LodCursor::move_to` against `extract_lod`\n\n");
  std::printf("%s  \n", run_header_line(load_at_start, load_average()).c_str());
  std::printf("Command: `%s`  \n", command_line("scan2lod_bench_cursor", argc, argv).c_str());
  std::printf("%s", openmp_line().c_str());
  const std::string revision = source_revision();
  if (!revision.empty()) std::printf("Source: %s (at run time)  \n", revision.c_str());
  std::printf("Input: %s: %zu nodes, %zu expansions, %lld triangles at full detail\n\n", source.c_str(),
              octree.tree.size(), octree.lod.full(), (long long)octree.lod.accumulated[octree.lod.full()]);
  std::printf("Times in µs, median (mean) over every timed move of %d runs, %s. Ratio: `extract_lod` over "
              "`move_to`, of the medians and of the totals.\n\n",
              reps, warm ? "caches warm (`--warm`)" : "caches flushed before every timed call");
  std::printf("| moves | timed | expansions per move | rebuilt | nodes re-emitted per move | triangles at target | "
              "`move_to` | µs per expansion | `extract_lod`, 1 thread | ratio (median / total) | "
              "`extract_lod`, %d threads | ratio (median / total) |\n",
              threads);
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& [c, r] : results) {
    const double n = double(r.move.size());
    std::printf("| %s | %zu | %.0f | %.0f %% | %.0f | %.0f | %s (%s) | %.2f | %s (%s) | %s / %s | %s (%s) | "
                "%s / %s |\n",
                c->name.c_str(), r.move.size(), r.expansions / n, 100 * r.rebuilt / n, r.emitted / n, r.triangles / n,
                us(median(r.move)).c_str(), us(sum(r.move) / n).c_str(), sum(r.move) / r.expansions * 1e6,
                us(median(r.extract_one)).c_str(),
                us(sum(r.extract_one) / n).c_str(), ratio(median(r.extract_one) / median(r.move)).c_str(),
                ratio(sum(r.extract_one) / sum(r.move)).c_str(), us(median(r.extract_all)).c_str(),
                us(sum(r.extract_all) / n).c_str(), ratio(median(r.extract_all) / median(r.move)).c_str(),
                ratio(sum(r.extract_all) / sum(r.move)).c_str());
  }
  std::printf("\nLevels are `priority_for_percent(p)` (the viewer's slider), so a 1 %% step is the distance "
              "between offered levels, not always 1 %% of the array. `move_to` includes the compaction it "
              "runs once holes pass a quarter of its buffer; *rebuilt*: moves that rebuilt the cut (under 32 cut "
              "nodes per expansion) rather than apply the expansions.\n");
  return 0;
}
