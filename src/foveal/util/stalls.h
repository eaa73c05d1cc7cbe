// foveal/util/stalls.h — how often, and for how long, this machine pauses a thread that is working.
//
// A frame loop on a deadline is late when the machine stops its threads for longer than the margin
// it keeps, whatever the renderer does. The probe tells such pauses apart on any machine, before an
// experiment: each thread repeats a fixed piece of arithmetic (no memory traffic, no system call) in
// chunks of about 100 µs, and times every chunk on the wall clock and on the thread's own CPU clock.
// A chunk far longer than its usual time is a stall, of one of two kinds:
// - off the CPU: the thread's CPU clock stood still — its kernel ran something else on that core
//   (another process, a kernel thread) or it was interrupted at length;
// - on the CPU: the thread's CPU clock ran with the wall clock, yet the same arithmetic took many
//   times longer — the core itself did not run it (a virtual CPU that its host paused without
//   counting the time as steal, or firmware taking the processor).
// Neither kind is the renderer's; the second cannot be seen by anything inside the machine but
// such a clock comparison.
#pragma once

#include "foveal/util/cpu_share.h"
#include "foveal/util/kernel_info.h"

#include <functional>
#include <vector>

namespace foveal {

struct StallProbeParams {
  double duration_s = 10;   // how long each thread works
  int threads = 0;          // 0: all the cores this process may use (util/parallel.h)
  double chunk_us = 100;    // the chunk's target duration (calibrated before the probe)
  double threshold_ms = 1;  // a chunk at least this long is a stall
  // Tests only: called after each chunk's work, before it is timed (to make a stall of either kind)
  std::function<void(int thread, long chunk)> inject;
};
// Check the parameters; throws Error naming the option.
void validate(const StallProbeParams& p);

struct Stall {
  int thread = 0;
  double at_s = 0;      // from the probe's start
  double wall_ms = 0;   // the chunk's wall time
  double cpu_ms = 0;    // … and its thread's CPU time
  bool on_cpu = false;  // the CPU clock ran for at least half the wall time
};
// The kind of a chunk's stall from its two clocks (pure; tests).
bool stalled_on_cpu(double wall_ms, double cpu_ms);

struct StallReport {
  int threads = 0;
  double duration_s = 0;            // measured, from the first chunk to the last
  double chunk_us = 0;              // the median chunk's wall time
  long chunks = 0;                  // over all threads
  std::vector<Stall> stalls;        // in the order of their start
  std::vector<BusyProcess> others;  // the other processes that ran meanwhile, the busiest first (util/cpu_share.h)
  KernelScheduling kernel;          // the kernel's tick and preemption model (util/kernel_info.h)
};
// Run the probe (the calling thread waits; each worker is a std::thread of its own).
StallReport probe_stalls(const StallProbeParams& p);

// One kind's figures over a report (pure; tests).
struct StallCounts {
  int count = 0;
  double per_minute = 0;  // over all threads together
  double worst_ms = 0;
  int longer_than_margin = 0;  // stalls whose time beyond a usual chunk exceeds the margin
};
StallCounts count_stalls(const StallReport& r, bool on_cpu, double margin_ms);

}  // namespace foveal
