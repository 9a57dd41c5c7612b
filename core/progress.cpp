#include "core/progress.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>

namespace scan2lod {
namespace {
std::atomic<bool> g_quiet{false};

long long now_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(steady_clock::now().time_since_epoch()).count();
}
}  // namespace

void Progress::set_quiet(bool quiet) { g_quiet = quiet; }
bool Progress::enabled() { return !g_quiet && isatty(fileno(stderr)); }

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)), total_(total), active_(enabled()) {
  if (active_) draw(0);
}

Progress::~Progress() { finish(); }

void Progress::advance(std::size_t n) {
  std::size_t done = done_.fetch_add(n) + n;
  if (!active_) return;
  long long t = now_ms();
  long long last = last_draw_ms_.load();
  if (t - last >= 100 && last_draw_ms_.compare_exchange_strong(last, t)) draw(done);
}

void Progress::finish() {
  if (!active_ || finished_) return;
  finished_ = true;
  draw(total_);
  std::fputc('\n', stderr);
}

void Progress::draw(std::size_t done) {
  const int width = 30;
  double f = total_ ? double(done) / double(total_) : 1.0;
  if (f > 1.0) f = 1.0;
  int filled = int(f * width);
  std::fprintf(stderr, "\r%-22s [%.*s%*s] %3d%%", label_.c_str(), filled,
               "##############################", width - filled, "", int(f * 100.0));
  std::fflush(stderr);
}

}  // namespace scan2lod
