// The CPU counters read from the kernel's text, and the shares between two readings.
#include "foveal/util/cpu_share.h"

#include <gtest/gtest.h>

#include <cmath>
#include <chrono>
#include <ctime>

namespace foveal {
namespace {

// Two readings whose differences are known: 1,000 ticks of all CPUs, 580 busy, of which 250 this
// process's (a command with a space and a parenthesis in its name), 50 stolen
TEST(CpuShare, OthersAndStealFromTwoReadings) {
  const CpuTimes a = parse_cpu_times("cpu  100 10 50 800 20 5 5 10 0 0\ncpu0 1 2 3 4 5 6 7 8 0 0\n",
                                     "4242 (foveal (bench)) R 1 2 3 4 5 6 7 8 9 10 200 40 0 0 20 0 9\n");
  const CpuTimes b =
      parse_cpu_times("cpu  500 10 230 1150 40 5 5 60 0 0\n", "4242 (foveal (bench)) R 1 2 3 4 5 6 7 8 9 10 400 90 0 0 20 0 9\n");
  ASSERT_TRUE(a.known && b.known);
  EXPECT_DOUBLE_EQ(b.total - a.total, 1000);
  EXPECT_DOUBLE_EQ(b.busy - a.busy, 580);
  EXPECT_DOUBLE_EQ(b.self - a.self, 250);
  const CpuShare s = cpu_share(a, b);
  EXPECT_DOUBLE_EQ(s.others, 0.33);
  EXPECT_DOUBLE_EQ(s.steal, 0.05);
}

TEST(CpuShare, MalformedOrMissingCountersAreUnknown) {
  const char* self = "1 (x) R 1 2 3 4 5 6 7 8 9 10 200 40\n";
  EXPECT_FALSE(parse_cpu_times("", self).known);
  EXPECT_FALSE(parse_cpu_times("cpu0 1 2 3 4 5 6 7 8\n", self).known);
  EXPECT_FALSE(parse_cpu_times("cpu  1 2 3\n", self).known);
  EXPECT_FALSE(parse_cpu_times("cpu  1 2 x 4 5 6 7 8\n", self).known);
  EXPECT_FALSE(parse_cpu_times("cpu  1 2 3 4 5 6 7 8\n", "1 x R 1 2").known);
  EXPECT_FALSE(parse_cpu_times("cpu  1 2 3 4 5 6 7 8\n", "1 (x) R 1 2 3").known);
  EXPECT_TRUE(parse_cpu_times("cpu  1 2 3 4 5 6 7 8\n", self).known);
  const CpuShare s = cpu_share(CpuTimes{}, CpuTimes{});
  EXPECT_TRUE(std::isnan(s.others) && std::isnan(s.steal));
}

// This machine's counters (Linux): a process that keeps a core busy is itself, not an other
TEST(CpuShare, OwnWorkIsNotCountedAsOthers) {
  const CpuTimes a = read_cpu_times();
  if (!a.known) GTEST_SKIP() << "no /proc/stat here";
  // 0.2 s of this process's CPU time (however busy the machine), at most 10 s of waiting for it
  volatile double sink = 0;
  const std::clock_t start = std::clock();
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::clock() - start < CLOCKS_PER_SEC / 5 && std::chrono::steady_clock::now() < give_up) sink = sink + std::sqrt(sink + 1);
  const CpuTimes b = read_cpu_times();
  ASSERT_TRUE(b.known);
  EXPECT_GE(b.self - a.self, 10);  // ~20 ticks at the kernel's 100 per second
  const CpuShare s = cpu_share(a, b);
  EXPECT_GE(s.others, 0);
  EXPECT_LE(s.others, 1);
}

}  // namespace
}  // namespace foveal
