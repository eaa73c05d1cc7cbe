// apps/bench_stalls.cpp — `foveal bench stalls`: how often this machine pauses a working thread, and
// of which kind (util/stalls.h), so that a lab can judge a machine before a gaze-contingent run.
#include "commands.h"
#include "foveal/render/outputs.h"
#include "foveal/render/realtime.h"
#include "foveal/experiments/stalls_report.h"
#include "foveal/util/parallel.h"

#include <fmt/core.h>

#include <cstdio>
#include <memory>

namespace foveal::app {

namespace {

struct BenchStallsOptions {
  double duration = 10, threshold_ms = 1, chunk_us = 100, margin_ms = kDefaultMarginMs;
  int threads = 0;
  std::string json, markdown;
};

int run_bench_stalls(const BenchStallsOptions& o) {
  validate_stall_margin(o.margin_ms);
  StallProbeParams p;
  p.duration_s = o.duration;
  p.threads = o.threads;
  p.threshold_ms = o.threshold_ms;
  p.chunk_us = o.chunk_us;
  validate(p);
  fmt::print("foveal bench stalls: {} s of fixed arithmetic on each of {} threads…\n", o.duration, thread_count(p.threads));
  std::fflush(stdout);
  const StallReport r = probe_stalls(p);
  const std::string md = stalls_markdown(r, o.threshold_ms, o.margin_ms);
  fmt::print("\n{}", md);
  if (!o.markdown.empty()) write_text_file(o.markdown, md);
  if (!o.json.empty()) write_json_file(o.json, stalls_json(r, o.threshold_ms, o.margin_ms));
  return 0;
}

}  // namespace

std::function<int()> add_bench_stalls_command(CLI::App& bench) {
  auto* cmd = bench.add_subcommand("stalls",
                                   "how often this machine pauses a working thread, off its CPU or on it: the late frames a real-time "
                                   "loop can expect from the machine itself");
  auto o = std::make_shared<BenchStallsOptions>();
  cmd->add_option("--duration", o->duration, "seconds each thread works")->capture_default_str();
  cmd->add_option("--threads", o->threads, "threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
  cmd->add_option("--threshold-ms", o->threshold_ms, "a chunk at least this long is a stall, ms")->capture_default_str();
  cmd->add_option("--chunk-us", o->chunk_us, "each chunk of arithmetic's usual duration, µs")->capture_default_str();
  cmd->add_option("--margin-ms", o->margin_ms, "the frame loop's margin the stalls are counted against, ms (the loop's default)")
      ->capture_default_str();
  cmd->add_option("--json", o->json, "write the figures and every stall as JSON")->check(output_file());
  cmd->add_option("--markdown", o->markdown, "write the table as Markdown")->check(output_file());
  return [o] { return run_bench_stalls(*o); };
}

}  // namespace foveal::app
