// foveal/experiments/stalls_report.cpp — the stall probe's figures as a table and as JSON.
#include "foveal/experiments/stalls_report.h"

#include "foveal/util/error.h"

#include <fmt/format.h>

namespace foveal {

namespace {

// Stalls beyond the margin a minute, over both kinds: at most the late frames a minute of a loop
// that works through every frame up to its deadline
double late_per_minute(const StallReport& r, double margin_ms) {
  const double minutes = r.duration_s / 60;
  return minutes > 0
             ? (count_stalls(r, false, margin_ms).longer_than_margin + count_stalls(r, true, margin_ms).longer_than_margin) / minutes
             : 0;
}

}  // namespace

void validate_stall_margin(double margin_ms) {
  if (!(margin_ms >= 0 && margin_ms < 1000)) fail("margin_ms: must be in [0, 1000) ms, got {}", margin_ms);
}

nlohmann::json others_json(const std::vector<BusyProcess>& others) {
  nlohmann::json j = nlohmann::json::array();
  for (const BusyProcess& b : others)
    j.push_back({{"pid", b.pid}, {"name", b.name}, {"kernel", b.kernel}, {"cpu_ms", b.cpu_ms}, {"slices", b.slices}});
  return j;
}

std::string others_sentence(const std::vector<BusyProcess>& others) {
  std::string s;
  for (const BusyProcess& b : others)
    s += fmt::format("{}{} ({}, pid {}) {:.1f} ms in {:.0f} turns", s.empty() ? "" : "; ", b.name.empty() ? "?" : b.name,
                     b.kernel ? "a kernel thread" : "a process", b.pid, b.cpu_ms, b.slices);
  return s;
}

nlohmann::json kernel_json(const KernelScheduling& k) {
  const auto text = [](const std::string& v) { return v.empty() ? nlohmann::json() : nlohmann::json(v); };
  return {{"release", text(k.release)},
          {"hz", k.hz > 0 ? nlohmann::json(k.hz) : nlohmann::json()},
          {"preempt", text(k.preempt)},
          {"source", text(k.source)}};
}

std::string kernel_sentence(const KernelScheduling& k, double margin_ms) {
  const std::string phrase = kernel_phrase(k);
  if (phrase.empty()) return {};
  const double tick_ms = 1000.0 / k.hz;
  return fmt::format(
      "Here {}: a thread that wakes takes a core from a working one once the latter's slice is spent, and may keep it to the "
      "next tick — up to {:.1f} ms, {} the {} ms margin; on Linux 6.6 and later (EEVDF) whatever the working thread's nice value "
      "(docs/realtime.md).",
      phrase, tick_ms, tick_ms > margin_ms ? "longer than" : "within", margin_ms);
}

nlohmann::json stalls_json(const StallReport& r, double threshold_ms, double margin_ms) {
  nlohmann::json j;
  j["threads"] = r.threads;
  j["duration_s"] = r.duration_s;
  j["chunks"] = r.chunks;
  j["chunk_us"] = r.chunk_us;
  j["threshold_ms"] = threshold_ms;
  j["margin_ms"] = margin_ms;
  const auto counts = [](const StallCounts& c) {
    return nlohmann::json{
        {"count", c.count}, {"per_minute", c.per_minute}, {"worst_ms", c.worst_ms}, {"beyond_margin", c.longer_than_margin}};
  };
  j["off_cpu"] = counts(count_stalls(r, false, margin_ms));
  j["on_cpu"] = counts(count_stalls(r, true, margin_ms));
  j["late_frames_per_minute_at_most"] = late_per_minute(r, margin_ms);
  j["others"] = others_json(r.others);
  j["kernel"] = kernel_json(r.kernel);
  j["stalls"] = nlohmann::json::array();
  for (const Stall& s : r.stalls)
    j["stalls"].push_back({{"thread", s.thread}, {"at_s", s.at_s}, {"wall_ms", s.wall_ms}, {"cpu_ms", s.cpu_ms}, {"on_cpu", s.on_cpu}});
  return j;
}

std::string stalls_markdown(const StallReport& r, double threshold_ms, double margin_ms) {
  const StallCounts off = count_stalls(r, false, margin_ms), on = count_stalls(r, true, margin_ms);
  const double late = late_per_minute(r, margin_ms);
  std::string md = fmt::format(
      "{} threads for {:.1f} s, {} chunks of fixed arithmetic (median {:.0f} µs); a stall is a chunk of at least {} ms.\n\n"
      "| stalls | count | per minute | beyond a {} ms margin | worst, ms |\n|---|---:|---:|---:|---:|\n",
      r.threads, r.duration_s, r.chunks, r.chunk_us, threshold_ms, margin_ms);
  md += fmt::format("| off the CPU: the thread's CPU clock stood still (its kernel ran something else) | {} | {:.1f} | {} | {:.1f} |\n",
                    off.count, off.per_minute, off.longer_than_margin, off.worst_ms);
  md += fmt::format(
      "| on the CPU: its CPU clock ran, the work did not (the core was paused: a host's virtual CPU, firmware) | {} | {:.1f} | {} | "
      "{:.1f} |\n\n",
      on.count, on.per_minute, on.longer_than_margin, on.worst_ms);
  md += fmt::format(
      "A frame loop keeping a {} ms margin (`view --realtime`, `replay --realtime`, `foveal.Loop`, `bench latency`) is late where "
      "such a stall, beyond the margin, falls into a frame it works through to its deadline: on this machine up to about {:.1f} "
      "late frames a minute for a loop that works through every frame, fewer where frames end early (a converged image costs "
      "little){}.\n",
      margin_ms, late, late > 0 ? " — late because of the machine, not the rendering" : "");
  if (!r.others.empty())
    md += fmt::format(
        "\nWhat else ran on this machine meanwhile, the busiest first, with its time on a CPU and in how many turns (what "
        "takes the working threads' cores: what to switch off or move before a session): {}.\n",
        others_sentence(r.others));
  if (const std::string k = kernel_sentence(r.kernel, margin_ms); !k.empty()) md += "\n" + k + "\n";
  return md;
}

}  // namespace foveal
