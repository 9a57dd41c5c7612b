#include <scan2lod/core/progress.h>

#include <chrono>
#include <utility>

namespace scan2lod {
namespace {
std::atomic<bool> g_quiet{false};
ProgressSink g_sink;

long long now_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(steady_clock::now().time_since_epoch()).count();
}
}  // namespace

void set_progress_sink(ProgressSink sink) { g_sink = std::move(sink); }
ProgressSink progress_sink() { return g_sink; }

void Progress::set_quiet(bool quiet) { g_quiet = quiet; }
bool Progress::enabled() { return !g_quiet && bool(g_sink); }

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)), total_(total), active_(enabled()) {
  if (active_) report(0, false);
}

Progress::~Progress() { finish(); }

void Progress::advance(std::size_t n) {
  const std::size_t done = done_.fetch_add(n) + n;
  if (!active_) return;
  const long long t = now_ms();
  long long last = last_report_ms_.load();
  if (t - last >= 100 && last_report_ms_.compare_exchange_strong(last, t)) report(done, false);
}

void Progress::finish() {
  if (!active_ || finished_) return;
  finished_ = true;
  report(total_, true);
}

void Progress::report(std::size_t done, bool finished) {
  double f = total_ ? double(done) / double(total_) : 1.0;
  if (f > 1.0) f = 1.0;
  g_sink(label_, f, finished);
}

}  // namespace scan2lod
