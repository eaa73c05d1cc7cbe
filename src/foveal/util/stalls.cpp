// foveal/util/stalls.cpp — a probe of the machine's pauses of working threads.
#include "foveal/util/stalls.h"

#include "foveal/util/cpu_share.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/stats.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <mutex>
#include <thread>

namespace foveal {

namespace {

double wall_ms_now() { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// The calling thread's CPU time, ms (POSIX: the thread's own CPU clock)
double cpu_ms_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) / 1e6;
}

// Fixed arithmetic on registers: n dependent multiply-adds (one copy of the code, so that the
// calibration times the very instructions the threads run)
[[gnu::noinline]] double work(long n, double x) {
  for (long i = 0; i < n; ++i) x = x * 1.0000001 + 1e-9;
  return x;
}

}  // namespace

void validate(const StallProbeParams& p) {
  if (!(p.duration_s > 0 && p.duration_s <= 3600)) fail("duration_s: must be in (0, 3600] seconds, got {}", p.duration_s);
  if (p.threads < 0 || p.threads > 4096) fail("threads: must be in [0, 4096] (0 = all cores), got {}", p.threads);
  if (!(p.chunk_us >= 10 && p.chunk_us <= 10000)) fail("chunk_us: must be in [10, 10000] µs, got {}", p.chunk_us);
  if (!(p.threshold_ms * 1000 >= 2 * p.chunk_us && p.threshold_ms <= 1000))
    fail("threshold_ms: must be at least twice the chunk ({} µs) and at most 1000 ms, got {}", p.chunk_us, p.threshold_ms);
}

bool stalled_on_cpu(double wall_ms, double cpu_ms) { return cpu_ms >= 0.5 * wall_ms; }

StallReport probe_stalls(const StallProbeParams& p) {
  validate(p);
  StallReport r;
  r.threads = thread_count(p.threads);
  // Calibrate the chunk on this thread: the least time of a few tries, so that a pause during
  // calibration does not shorten every chunk
  long n = 1000;
  double sink = 1;
  for (int tries = 0; tries < 20; ++tries) {
    double best = INFINITY;
    for (int k = 0; k < 5; ++k) {
      const double t0 = wall_ms_now();
      sink = work(n, sink);
      best = std::min(best, wall_ms_now() - t0);
    }
    const double want_ms = p.chunk_us / 1000;
    if (best > 0.8 * want_ms && best < 1.25 * want_ms) break;
    n = std::max(1L, static_cast<long>(static_cast<double>(n) * want_ms / std::max(best, 1e-6)));
  }
  std::mutex lock;
  std::vector<double> chunk_ms;
  volatile double kept = sink;  // the arithmetic's results, so that it is done
  const double start = wall_ms_now();
  double first = INFINITY, last = 0;
  auto body = [&](int thread) {
    std::vector<Stall> stalls;
    std::vector<double> times;
    double x = 1 + thread;
    double w0 = wall_ms_now(), c0 = cpu_ms_now();
    const double begin = w0, end = w0 + p.duration_s * 1000;
    long chunk = 0;
    while (w0 < end) {
      x = work(n, x);
      if (p.inject) p.inject(thread, chunk);
      const double w1 = wall_ms_now(), c1 = cpu_ms_now();
      if (w1 - w0 >= p.threshold_ms) stalls.push_back({thread, (w0 - start) / 1000, w1 - w0, c1 - c0, stalled_on_cpu(w1 - w0, c1 - c0)});
      if (times.size() < 100000) times.push_back(w1 - w0);
      ++chunk;
      w0 = w1;
      c0 = c1;
    }
    const std::lock_guard<std::mutex> guard(lock);
    r.chunks += chunk;
    r.stalls.insert(r.stalls.end(), stalls.begin(), stalls.end());
    chunk_ms.insert(chunk_ms.end(), times.begin(), times.end());
    first = std::min(first, begin);
    last = std::max(last, w0);
    kept = kept + x;
  };
  const MachineThreads census = read_machine_threads();  // what else runs meanwhile (read before and after)
  std::vector<std::thread> workers;
  for (int t = 0; t < r.threads; ++t) workers.emplace_back(body, t);
  for (std::thread& w : workers) w.join();
  r.others = busiest_others(census, read_machine_threads(), current_process_id(), kBusiestOthers);
  r.kernel = read_kernel_scheduling();
  std::sort(r.stalls.begin(), r.stalls.end(), [](const Stall& a, const Stall& b) { return a.at_s < b.at_s; });
  r.duration_s = (last - first) / 1000;
  r.chunk_us = chunk_ms.empty() ? 0 : 1000 * median(chunk_ms);
  return r;
}

StallCounts count_stalls(const StallReport& r, bool on_cpu, double margin_ms) {
  StallCounts c;
  for (const Stall& s : r.stalls) {
    if (s.on_cpu != on_cpu) continue;
    ++c.count;
    c.worst_ms = std::max(c.worst_ms, s.wall_ms);
    c.longer_than_margin += s.wall_ms - r.chunk_us / 1000 > margin_ms ? 1 : 0;
  }
  c.per_minute = r.duration_s > 0 ? c.count * 60.0 / r.duration_s : 0;
  return c;
}

}  // namespace foveal
