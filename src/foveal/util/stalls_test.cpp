// The probe of the machine's pauses: its two kinds told apart by the thread's two clocks.
#include "foveal/util/stalls.h"

#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <chrono>
#include <ctime>
#include <thread>

namespace foveal {
namespace {

TEST(Stalls, TheKindFollowsTheThreadsCpuClock) {
  EXPECT_TRUE(stalled_on_cpu(5.0, 4.9));  // the clock ran: the core did not run the work
  EXPECT_TRUE(stalled_on_cpu(5.0, 2.5));
  EXPECT_FALSE(stalled_on_cpu(5.0, 2.4));  // the clock stood still: the thread was off its core
  EXPECT_FALSE(stalled_on_cpu(7.3, 0.17));
}

TEST(Stalls, CountsPerKindAndAgainstTheMargin) {
  StallReport r;
  r.duration_s = 30;
  r.chunk_us = 100;
  r.stalls = {{0, 1, 1.5, 1.5, true}, {1, 2, 14.7, 14.6, true}, {0, 3, 7.3, 0.2, false}, {1, 4, 2.05, 0.1, false}};
  const StallCounts on = count_stalls(r, true, 2.0), off = count_stalls(r, false, 2.0);
  EXPECT_EQ(on.count, 2);
  EXPECT_DOUBLE_EQ(on.per_minute, 4);
  EXPECT_DOUBLE_EQ(on.worst_ms, 14.7);
  EXPECT_EQ(on.longer_than_margin, 1);  // 14.6 ms beyond a chunk; 1.4 ms is within 2
  EXPECT_EQ(off.count, 2);
  EXPECT_EQ(off.longer_than_margin, 1);  // 7.2 ms; 2.05 − 0.1 = 1.95 ms is within 2
  EXPECT_EQ(count_stalls(StallReport{}, true, 2.0).count, 0);
}

TEST(Stalls, BadParametersAreRefused) {
  StallProbeParams p;
  p.duration_s = 0;
  EXPECT_THROW(validate(p), Error);
  p = {};
  p.threads = -1;
  EXPECT_THROW(validate(p), Error);
  p = {};
  p.chunk_us = 5;
  EXPECT_THROW(validate(p), Error);
  p = {};
  p.threshold_ms = 0.1;  // under twice the chunk: every chunk would be a stall
  EXPECT_THROW(validate(p), Error);
  p = {};
  p.duration_s = NAN;
  EXPECT_THROW(validate(p), Error);
  EXPECT_NO_THROW(validate(StallProbeParams{}));
}

// Stalls made on purpose: thread 0 sleeps 20 ms after its 300th chunk (off its core), thread 1
// spins 20 ms on its own CPU clock after its 300th (on it). Both are found with their clocks: the
// sleep with its CPU clock nearly still, so off the CPU however busy the machine; the spin with 20
// ms on its CPU clock, so on the CPU unless the machine's other work more than doubled its wall
// time (a stall of the machine's own may come too; these two must)
TEST(Stalls, AStallOfEachKindIsFoundAndToldApart) {
  StallProbeParams p;
  p.duration_s = 0.3;
  p.threads = 2;
  p.threshold_ms = 1;
  p.inject = [](int thread, long chunk) {
    if (chunk != 300) return;
    if (thread == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    } else {
      timespec t0{}, t{};
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
      do clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
      while ((t.tv_sec - t0.tv_sec) * 1e3 + (t.tv_nsec - t0.tv_nsec) / 1e6 < 20);
    }
  };
  const StallReport r = probe_stalls(p);
  EXPECT_EQ(r.threads, 2);
  EXPECT_GT(r.chunks, 600);
  EXPECT_GT(r.chunk_us, 10);
  EXPECT_LT(r.chunk_us, 1000);
  EXPECT_GE(r.duration_s, 0.29);
  bool slept = false, spun = false;
  for (const Stall& s : r.stalls) {
    EXPECT_LE(s.cpu_ms, s.wall_ms + 0.5);
    EXPECT_EQ(s.on_cpu, stalled_on_cpu(s.wall_ms, s.cpu_ms));
    if (s.thread == 0 && s.wall_ms >= 20 && s.cpu_ms < 5 && !s.on_cpu) slept = true;
    if (s.thread == 1 && s.wall_ms >= 20 && s.cpu_ms >= 19.5) spun = true;
  }
  EXPECT_TRUE(slept) << "thread 0's sleep not found off the CPU";
  // What else ran meanwhile: other processes only, the busiest first, at most kBusiestOthers
  EXPECT_LE(r.others.size(), kBusiestOthers);
  for (size_t k = 0; k < r.others.size(); ++k) {
    EXPECT_NE(r.others[k].pid, current_process_id());
    EXPECT_GT(r.others[k].cpu_ms, 0);
    if (k > 0) EXPECT_LE(r.others[k].cpu_ms, r.others[k - 1].cpu_ms);
  }
  EXPECT_TRUE(spun) << "thread 1's spin not found on the CPU";
}

}  // namespace
}  // namespace foveal
