// foveal/util/kernel_info.h — the running kernel's tick and preemption model, read where Linux
// states them, so that a report on a machine's pauses can say how long another thread may keep a
// core.
//
// A thread that wakes on a busy core gets its turn once the working thread's slice is spent, and
// the scheduler looks again at the next tick of the kernel's clock (or when another thread wakes):
// without a high-resolution tick, another process's turn lasts up to one tick — 4 ms at 250 Hz,
// 1 ms at 1000 Hz. On Linux 6.6 and later (EEVDF) that holds whatever the working thread's nice
// value: a woken thread's turn comes from its lag, not its weight (docs/realtime.md has the trace).
// The preemption model says where the kernel's own code may be interrupted: `none` and `voluntary`
// only where it yields, `full` anywhere outside critical sections, `rt` (PREEMPT_RT) nearly anywhere.
#pragma once

#include <string>
#include <string_view>

namespace foveal {

struct KernelScheduling {
  std::string release;  // uname's release ("6.18.44-…"; "" where unknown)
  int hz = 0;           // CONFIG_HZ, ticks a second (0 where unknown)
  std::string preempt;  // none, voluntary, full, lazy or rt ("" where unknown)
  std::string source;  // where they were read ("/proc/config.gz", "/boot/config-…", then the boot line or debugfs where it chose the model)
};

// From the texts of a kernel config, the kernel's command line and debugfs's sched/preempt (any may
// be empty; pure): CONFIG_HZ; the preemption model from PREEMPT_RT, else the mode debugfs marks
// "(full)", else a preempt= on the command line of a PREEMPT_DYNAMIC kernel, else the config's
// default (PREEMPT_NONE, PREEMPT_VOLUNTARY, PREEMPT, PREEMPT_LAZY).
KernelScheduling parse_kernel_scheduling(std::string_view config, std::string_view cmdline, std::string_view debugfs_preempt);
// This machine's (Linux: /proc/config.gz or /boot/config-RELEASE, /proc/cmdline,
// /sys/kernel/debug/sched/preempt where readable); the fields stay empty where nothing states them.
KernelScheduling read_kernel_scheduling();
// "the kernel (6.18.44) ticks at 250 Hz, preemption none (/proc/config.gz)" ("" where the tick is unknown)
std::string kernel_phrase(const KernelScheduling& k);

}  // namespace foveal
