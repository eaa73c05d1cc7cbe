// foveal/experiments/stalls_report.h — the stall probe's figures (util/stalls.h) as `foveal bench
// stalls` and `foveal.stalls()` give them: a Markdown table and a JSON document.
#pragma once

#include "foveal/util/stalls.h"

#include <nlohmann/json.hpp>

#include <string>

namespace foveal {

// The figures against a frame loop's margin (ms): per kind (`off_cpu`, `on_cpu`: count, per_minute,
// beyond_margin, worst_ms), the probe (threads, duration_s, chunks, chunk_us, threshold_ms,
// margin_ms), late_frames_per_minute_at_most and every stall.
nlohmann::json stalls_json(const StallReport& r, double threshold_ms, double margin_ms);
// The table and what it means for a frame loop.
// The other processes that ran during a run, as JSON (pid, name, kernel, cpu_ms, slices) and as a
// sentence ("kdamond.0 (a kernel thread, pid 77) 59.8 ms in 44 turns; …"; empty where none ran)
nlohmann::json others_json(const std::vector<BusyProcess>& others);
std::string others_sentence(const std::vector<BusyProcess>& others);
std::string stalls_markdown(const StallReport& r, double threshold_ms, double margin_ms);
// The kernel's tick and preemption model as JSON (release, hz, preempt, source; null where unknown)
// and as a sentence on how long another thread may keep a core, against a loop's margin ("" where
// the tick is unknown)
nlohmann::json kernel_json(const KernelScheduling& k);
std::string kernel_sentence(const KernelScheduling& k, double margin_ms);
// Check a margin; throws Error naming margin_ms.
void validate_stall_margin(double margin_ms);

}  // namespace foveal
