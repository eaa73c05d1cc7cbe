// foveal/util/cpu_share.h — how much of the machine's CPU time went to other processes, and to the
// hypervisor, while a run was timed.
//
// A timed run on a shared machine measures the machine as much as the program: a frame comes late
// when another process or the hypervisor takes its core. Two readings of the kernel's counters
// (Linux: /proc/stat for all CPUs, /proc/self/stat for this process, in clock ticks) around the run
// give the share of all CPUs' time that others were busy, and the share stolen by the hypervisor, so
// that a benchmark can say whether its late frames may be theirs.
#pragma once

#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace foveal {

// The counters at one moment, in clock ticks (known = false where they could not be read).
struct CpuTimes {
  double total = 0;  // all CPUs: user, nice, system, idle, iowait, irq, softirq, steal
  double busy = 0;   // of which not idle, waiting for I/O or stolen
  double steal = 0;  // taken by the hypervisor for other machines
  double self = 0;   // this process (all its threads): user and system
  bool known = false;
};

// The counters from the text of /proc/stat and /proc/self/stat (known = false where either is
// malformed).
CpuTimes parse_cpu_times(std::string_view proc_stat, std::string_view self_stat);
// The counters now (known = false where /proc is not there).
CpuTimes read_cpu_times();

// Between two readings, as fractions of all CPUs' time (NaN where unknown or no time passed).
struct CpuShare {
  double others = NAN;  // other processes busy (this process's own time left out)
  double steal = NAN;   // stolen by the hypervisor
};
CpuShare cpu_share(const CpuTimes& before, const CpuTimes& after);

// Each thread of this process: how long it has run, and how long it has waited, runnable, for a
// CPU — the kernel's run delay (Linux: /proc/self/task/TID/schedstat, "run_ns wait_ns timeslices").
// A thread that the kernel takes off its core for something else (another process, a kernel
// thread) waits there; one that sleeps or blocks does not. Around a frame they tell whether a late
// frame's threads were kept off their cores by this machine's kernel, or ran the whole time and
// the work itself took longer.
struct ThreadTime {
  double run_ns = 0, wait_ns = 0;
  double slices = 0;  // times it was put on a CPU
};
using ThreadTimes = std::unordered_map<long, ThreadTime>;  // thread id → its times
// One schedstat file's times (nullopt where malformed).
std::optional<ThreadTime> parse_schedstat(std::string_view schedstat);
// Every thread's times now (empty where /proc is not there).
ThreadTimes read_thread_times();
// Between two readings, over the threads in both (NaN where none is): the longest any thread
// waited for a CPU, and the time on a CPU of all threads together or of thread `only`, ms.
double longest_wait_ms(const ThreadTimes& before, const ThreadTimes& after);
double cpu_ms(const ThreadTimes& before, const ThreadTimes& after, long only = -1);
// The calling thread's id in those readings (−1 where there is none).
long current_thread_id();
// What else ran on this machine while a run was timed, by process: every thread of every process
// (Linux: /proc/PID/task/TID/schedstat, with the process's name from /proc/PID/comm and whether it
// is the kernel's own from the PF_KTHREAD flag of /proc/PID/stat). Around a run, the processes
// that took the most CPU time name what a lab would switch off or move before a gaze-contingent
// session (a memory monitor of the kernel, an agent of the host, a desktop indexer, …). Threads
// that ended before the second reading are not counted; one born between the two counts from zero.
struct ProcessThreads {
  std::string name;                              // the process's command name
  bool kernel = false;                           // a kernel thread
  std::unordered_map<long, ThreadTime> threads;  // thread id → its times
};
using MachineThreads = std::unordered_map<long, ProcessThreads>;  // process id →
// Whether a /proc/PID/stat text is a kernel thread's (its flags hold PF_KTHREAD; nullopt where malformed).
std::optional<bool> parse_kernel_thread(std::string_view stat);
// Every process's threads now (empty where /proc is not there).
MachineThreads read_machine_threads();
struct BusyProcess {
  long pid = 0;
  std::string name;
  bool kernel = false;
  double cpu_ms = 0;  // its threads' time on a CPU between the readings
  double slices = 0;  // … in this many turns
};
// The processes other than `self_pid` that ran between two readings, the busiest first, at most `most`.
std::vector<BusyProcess> busiest_others(const MachineThreads& before, const MachineThreads& after, long self_pid, size_t most);
inline constexpr size_t kBusiestOthers = 5;  // how many of them a report names (bench stalls, bench latency)
// A few other processes' threads read cheaply around each frame (one schedstat file each): those
// that ran between two readings of the machine, the `most` busiest of them — the likely takers of a
// frame's cores.
struct WatchedThread {
  long pid = 0, tid = 0;
  std::string name;  // the process's
  bool kernel = false;
  std::string schedstat;  // its file
};
std::vector<WatchedThread> threads_to_watch(const MachineThreads& before, const MachineThreads& after, long self_pid, size_t most);
// The watched threads' times now (thread id → times; a thread that ended is left out).
ThreadTimes read_watched(const std::vector<WatchedThread>& watch);
// The watched process that ran longest between two readings, and its time on a CPU, ms ("" and 0
// where none ran).
std::pair<std::string, double> busiest_watched(const std::vector<WatchedThread>& watch, const ThreadTimes& before,
                                               const ThreadTimes& after);

// This process's id (−1 where there is none).
long current_process_id();

// This process's page faults so far, minor and major (getrusage; NaN where it fails).
double page_faults();

}  // namespace foveal
