// The CPU counters read from the kernel's text, and the shares between two readings.
#include "foveal/util/cpu_share.h"

#include <gtest/gtest.h>

#include <cmath>
#include <chrono>
#include <ctime>
#include <thread>

#include <algorithm>
#include <csignal>

#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

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

// A thread's times are schedstat's first two fields ("run_ns wait_ns timeslices"), in nanoseconds
TEST(CpuShare, ThreadTimesFromSchedstat) {
  const std::optional<ThreadTime> t = parse_schedstat("571401700 358793 70\n");
  ASSERT_TRUE(t);
  EXPECT_DOUBLE_EQ(t->run_ns, 571401700);
  EXPECT_DOUBLE_EQ(t->wait_ns, 358793);
  EXPECT_DOUBLE_EQ(t->slices, 70);
  EXPECT_DOUBLE_EQ(parse_schedstat("5 6\n")->slices, 0);  // (an older kernel's two fields)
  EXPECT_FALSE(parse_schedstat("5 6 x\n"));
  EXPECT_FALSE(parse_schedstat(""));
  EXPECT_FALSE(parse_schedstat("571401700\n"));
  EXPECT_FALSE(parse_schedstat("571401700 -3 70\n"));
  EXPECT_FALSE(parse_schedstat("x 358793 70\n"));
  // Between two readings, over the threads in both (thread 8 was not there before): the longest
  // wait 2.5 ms, 4 + 1 ms on a CPU
  const ThreadTimes a{{7, {10e6, 1e6}}, {9, {20e6, 3e6}}}, b{{7, {14e6, 3.5e6}}, {9, {21e6, 3.2e6}}, {8, {50e6, 9e6}}};
  EXPECT_DOUBLE_EQ(longest_wait_ms(a, b), 2.5);
  EXPECT_DOUBLE_EQ(cpu_ms(a, b), 5);
  EXPECT_DOUBLE_EQ(cpu_ms(a, b, 9), 1);
  EXPECT_TRUE(std::isnan(cpu_ms(a, b, 8)));
  EXPECT_TRUE(std::isnan(longest_wait_ms({}, b)) && std::isnan(cpu_ms({}, b)));
}

// This machine's threads (Linux): the calling thread and a second one are both read, no thread's
// times go down, and a thread that spins for 0.1 s of its CPU time shows it
TEST(CpuShare, EveryThreadsTimesAreRead) {
  const ThreadTimes a = read_thread_times();
  if (a.empty()) GTEST_SKIP() << "no /proc/self/task/*/schedstat here";
  const long self = current_thread_id();
  EXPECT_EQ(self, static_cast<long>(::syscall(SYS_gettid)));
  EXPECT_TRUE(a.count(self));
  long other = 0;
  ThreadTimes start, during;
  std::thread t([&] {
    other = current_thread_id();
    start = read_thread_times();
    volatile double sink = 0;
    const std::clock_t begin = std::clock();
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::clock() - begin < CLOCKS_PER_SEC / 10 && std::chrono::steady_clock::now() < give_up) sink = sink + std::sqrt(sink + 1);
    during = read_thread_times();
  });
  t.join();
  ASSERT_TRUE(start.count(other) && during.count(self) && during.count(other));
  EXPECT_GE(during.at(other).run_ns - start.at(other).run_ns, 0.05e9);
  EXPECT_GE(cpu_ms(start, during, other), 50);
  const ThreadTimes b = read_thread_times();
  EXPECT_FALSE(b.count(other));  // ended
  for (const auto& [tid, times] : b)
    if (a.count(tid)) {
      EXPECT_GE(times.run_ns, a.at(tid).run_ns) << "thread " << tid;
      EXPECT_GE(times.wait_ns, a.at(tid).wait_ns) << "thread " << tid;
    }
  EXPECT_GE(longest_wait_ms(a, b), 0);
}

// A process's stat flags hold PF_KTHREAD (0x00200000) for the kernel's own threads; a command may
// hold spaces and parentheses
TEST(CpuShare, KernelThreadsAreToldFromTheirFlags) {
  EXPECT_EQ(parse_kernel_thread("77 (kdamond.0) I 2 0 0 0 -1 2129984 0 0 0 0 0 3390\n"), true);
  EXPECT_EQ(parse_kernel_thread("1 (process_api) S 0 1 1 0 -1 4194560 6000 0 0 0 12 7\n"), false);
  EXPECT_EQ(parse_kernel_thread("42 (a (b) c) R 1 42 42 0 -1 4194304 0 0\n"), false);
  EXPECT_EQ(parse_kernel_thread("42 (x) R 1 42 42 0 -1 2097152\n"), true);
  EXPECT_FALSE(parse_kernel_thread(""));
  EXPECT_FALSE(parse_kernel_thread("42 (x) R 1 42\n"));
  EXPECT_FALSE(parse_kernel_thread("42 (x) R 1 42 42 0 -1 flags\n"));
}

// Between two readings, the other processes by their threads' time on a CPU: this process left
// out, a thread born between them counted from zero, one process's threads summed, the busiest
// first, at most `most`
TEST(CpuShare, TheBusiestOtherProcessesBetweenTwoReadings) {
  MachineThreads a, b;
  a[1] = {"init", false, {{1, {100e6, 0, 10}}, {2, {50e6, 0, 5}}}};
  a[77] = {"kdamond.0", true, {{77, {900e6, 0, 100}}}};
  a[500] = {"foveal", false, {{500, {10e9, 0, 1000}}}};
  b = a;
  b[1].threads[1] = {104e6, 0, 14};
  b[1].threads[3] = {2e6, 0, 2};  // born between
  b[77].threads[77] = {960e6, 0, 144};
  b[500].threads[500] = {20e9, 0, 2000};              // this process
  b[600] = {"indexer", false, {{600, {1e6, 0, 1}}}};  // a process started between
  const std::vector<BusyProcess> top = busiest_others(a, b, 500, 10);
  ASSERT_EQ(top.size(), 3u);  // (init's thread 2 did not run: no time, and nothing of 500)
  EXPECT_EQ(top[0].name, "kdamond.0");
  EXPECT_TRUE(top[0].kernel);
  EXPECT_DOUBLE_EQ(top[0].cpu_ms, 60);
  EXPECT_DOUBLE_EQ(top[0].slices, 44);
  EXPECT_EQ(top[1].pid, 1);
  EXPECT_DOUBLE_EQ(top[1].cpu_ms, 6);
  EXPECT_DOUBLE_EQ(top[1].slices, 6);
  EXPECT_EQ(top[2].name, "indexer");
  EXPECT_DOUBLE_EQ(top[2].cpu_ms, 1);
  EXPECT_EQ(busiest_others(a, b, 500, 1).size(), 1u);
  EXPECT_TRUE(busiest_others(a, a, 500, 10).empty());
}

// On this machine (Linux): a child process that spins for 0.1 s of CPU time under a name of its own
// is found, with that time, and this process is not
TEST(CpuShare, AnotherProcessThatRanIsFoundByName) {
  const MachineThreads before = read_machine_threads();
  if (before.empty()) GTEST_SKIP() << "no /proc here";
  EXPECT_TRUE(before.count(current_process_id()));
  int go[2];
  ASSERT_EQ(::pipe(go), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // only async-signal-safe calls and arithmetic here
    ::prctl(PR_SET_NAME, "census-spin");
    volatile double sink = 0;
    timespec t0{}, t{};
    ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
    do {
      for (int k = 0; k < 10000; ++k) sink = sink + 1.0;
      ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    } while ((t.tv_sec - t0.tv_sec) * 1e9 + (t.tv_nsec - t0.tv_nsec) < 0.1e9);
    char c = 1;
    (void)!::write(go[1], &c, 1);  // spun: the parent may read the machine again
    ::pause();
    ::_exit(0);
  }
  char c = 0;
  const bool spun = ::read(go[0], &c, 1) == 1;
  const MachineThreads after = read_machine_threads();
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  ::close(go[0]);
  ::close(go[1]);
  ASSERT_TRUE(spun);
  const std::vector<BusyProcess> top = busiest_others(before, after, current_process_id(), after.size());
  const auto it = std::find_if(top.begin(), top.end(), [&](const BusyProcess& b) { return b.pid == child; });
  ASSERT_NE(it, top.end());
  EXPECT_EQ(it->name, "census-spin");
  EXPECT_FALSE(it->kernel);
  EXPECT_GE(it->cpu_ms, 90);
  EXPECT_GE(it->slices, 1);
  for (const BusyProcess& b : top) EXPECT_NE(b.pid, current_process_id());
}

// Around a frame, the watched threads of other processes: the process whose threads ran longest
// between two readings, by name, with its time (two threads of one process summed)
TEST(CpuShare, TheOtherProcessBusiestInAFrame) {
  const std::vector<WatchedThread> watch{{1, 10, "agent", false, ""}, {1, 11, "agent", false, ""}, {77, 77, "kdamond.0", true, ""}};
  const ThreadTimes a{{10, {1e6, 0, 1}}, {11, {1e6, 0, 1}}, {77, {5e6, 0, 1}}};
  ThreadTimes b{{10, {2.5e6, 0, 2}}, {11, {3e6, 0, 2}}, {77, {8e6, 0, 2}}};
  EXPECT_EQ(busiest_watched(watch, a, b), std::make_pair(std::string("agent"), 3.5));
  b[77].run_ns = 9e6;
  EXPECT_EQ(busiest_watched(watch, a, b), std::make_pair(std::string("kdamond.0"), 4.0));
  EXPECT_EQ(busiest_watched(watch, a, a), std::make_pair(std::string(), 0.0));
  EXPECT_EQ(busiest_watched({}, a, b), std::make_pair(std::string(), 0.0));
  // What is watched: the threads of other processes that ran between two readings of the machine,
  // the busiest first, at most `most` (this process's, and a thread that did not run, left out)
  MachineThreads before, after;
  before[1] = {"agent", false, {{10, {1e6, 0, 1}}, {11, {1e6, 0, 1}}}};
  before[500] = {"foveal", false, {{500, {1e9, 0, 1}}}};
  after = before;
  after[1].threads[10].run_ns = 3e6;
  after[500].threads[500].run_ns = 2e9;
  after[77] = {"kdamond.0", true, {{77, {5e6, 0, 3}}}};
  const std::vector<WatchedThread> w = threads_to_watch(before, after, 500, 8);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].tid, 77);
  EXPECT_TRUE(w[0].kernel);
  EXPECT_EQ(w[0].schedstat, "/proc/77/task/77/schedstat");
  EXPECT_EQ(w[1].tid, 10);
  EXPECT_EQ(w[1].name, "agent");
  EXPECT_EQ(threads_to_watch(before, after, 500, 1).size(), 1u);
}

// Touching 8 MB of fresh memory faults its pages in: at least one fault per 2 MB, the largest page
// the kernel may give it (with 4 kB pages about 2,000). The memory is a fresh mapping of its own:
// from the allocator, 8 MB can be memory an earlier test touched and freed (once large blocks have
// been freed, glibc serves blocks up to 32 MB from its heap), which faults nothing — as it did
// when the tests ran in another order.
TEST(CpuShare, PageFaultsCountFreshMemoryTouched) {
  const size_t n = 8u << 20;
  void* const mapped = mmap(nullptr, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(mapped, MAP_FAILED);
  const double before = page_faults();
  ASSERT_FALSE(std::isnan(before));
  auto* block = static_cast<volatile char*>(mapped);
  for (size_t i = 0; i < n; i += 4096) block[i] = 1;
  const double faults = page_faults() - before;
  munmap(mapped, n);
  EXPECT_GE(faults, 4);
}

}  // namespace
}  // namespace foveal
