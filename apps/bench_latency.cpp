// apps/bench_latency.cpp — `foveal bench latency`: gaze-to-photon latency of the whole-frame loop,
// the deadline loop and the deadline loop with saccade landing prediction, on recorded gaze.
#include "commands.h"
#include "foveal/io/plot.h"
#include "foveal/experiments/latency.h"
#include "foveal/render/outputs.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/util/text.h"

#include <fmt/core.h>

#include <cmath>
#include <filesystem>
#include <memory>

namespace foveal::app {

namespace {

struct BenchLatencyOptions {
  std::string scene, camera, size = "840x525", display = "47.5,30,60,1680,1050", clock = "wall", device = "cpu";
  std::string json, markdown, timeline, loops = "whole-frame,deadline,deadline+prediction", landing;
  std::vector<std::string> recordings;
  double start = 0, duration = 3, refresh_hz = 60, min_amplitude = 2;
  std::optional<double> budget_ms, latency_ms, model_rays_per_ms, model_fixed_ms;
  LoopOptions loop;
  int max_rays = 400, threads = 0, timeline_saccade = 0;
  double tolerance = AoReuseParams{}.tolerance;
  uint64_t seed = 1;
};

int run_bench_latency(const BenchLatencyOptions& o) {
  const ThreadScope threads(o.threads);
  std::string spec = o.scene;
  const Scene scene = load_paper_scene(spec, "bench latency");
  ViewOptions view;
  view.camera = o.camera;
  const Camera camera = resolve_camera(scene, view);
  LatencyParams p;
  const glm::ivec2 size = parse_size("--size", o.size);
  p.render.width = size.x;
  p.render.height = size.y;
  p.render.display = resolve_display(o.display, size);
  p.render.foveation.max_rays = o.max_rays;
  p.render.seed = o.seed;
  p.render.reuse.tolerance = o.tolerance;
  p.refresh_hz = o.refresh_hz;
  p.budget_ms = o.budget_ms;
  p.tracker_latency_ms = o.latency_ms;
  p.margin_ms = o.loop.margin_ms;
  p.periphery_share = o.loop.periphery_share.value_or(kDefaultPeripheryShare);
  p.rays_ahead = !o.loop.no_rays_ahead;
  p.min_scale = o.loop.min_scale.value_or(kDefaultMinScale);
  p.clock = parse_loop_clock(o.clock);
  p.model_rays_per_ms = o.model_rays_per_ms;
  p.model_fixed_ms = o.model_fixed_ms;
  p.start_s = o.start;
  p.duration_s = o.duration;
  p.min_amplitude_deg = o.min_amplitude;
  p.landing = resolve_landing(o.landing);
  if (!o.timeline.empty()) p.timeline_saccade = static_cast<size_t>(o.timeline_saccade);
  p.loops.clear();
  for (const std::string_view name : text::split(o.loops, ',')) p.loops.emplace_back(name);
  validate(p);
  std::vector<std::string> paths = o.recordings;
  if (paths.empty()) {
    const std::string eyelink =  // (written without the "..": it heads the tables)
        std::filesystem::path(std::string(FOVEAL_SOURCE_DIR) + "/../shared/data/gaze/eyelink/monoRemote500.asc")
            .lexically_normal()
            .string();
    if (!std::filesystem::exists(eyelink)) fail("--recording: none given, and the shared EyeLink recording is absent ({})", eyelink);
    paths.push_back(eyelink);
  }
  ReadOptions read;
  read.screen_px = {p.render.display.res_x, p.render.display.res_y};
  read.display_width_cm = p.render.display.width_cm;
  read.display_height_cm = p.render.display.height_cm;
  read.display_distance_cm = p.render.display.distance_cm;
  std::vector<Recording> recordings;
  for (const std::string& path : paths) recordings.push_back(read_recording_warned(path, read));
  const ComputeDevice device = choose_device(o.device);
  const LatencyReport report = bench_latency(scene, spec, camera, device, threads.threads(), recordings, p, [](const std::string& line) {
    fmt::print("{}\n", line);
    std::fflush(stdout);
  });
  fmt::print("\n{}", report.markdown);
  if (!o.json.empty()) write_json_file(o.json, report.json);
  if (!o.markdown.empty()) write_text_file(o.markdown, report.markdown);
  if (!o.timeline.empty()) {
    const size_t k = write_latency_timeline(report, o.min_amplitude, o.timeline);
    fmt::print("timeline of saccade {} written to {}\n", k, o.timeline);
    if (const std::string note = latency_timeline_note(report, static_cast<size_t>(o.timeline_saccade), "--timeline-saccade ");
        !note.empty())
      fmt::print("  ({})\n", note);
  }
  return 0;
}

}  // namespace

std::function<int()> add_bench_latency_command(CLI::App& bench) {
  auto* cmd = bench.add_subcommand("latency",
                                   "gaze-to-photon latency: replays recordings through the whole-frame loop, the deadline loop and the "
                                   "deadline loop with saccade landing prediction under a simulated display clock");
  auto o = std::make_shared<BenchLatencyOptions>();
  cmd->add_option("--recording", o->recordings,
                  "gaze recording (repeatable; any format `foveal gaze` reads; default: the shared EyeLink recording "
                  "monoRemote500.asc)");
  cmd->add_option("--start", o->start, "segment start, seconds from the recording's first sample")->capture_default_str();
  cmd->add_option("--duration", o->duration, "segment length, seconds")->capture_default_str();
  cmd->add_option("--scene", o->scene,
                  "scene (default: scenes/dragon-box.json, the paper's dragon in a box; builtin:box when the dragon is absent)");
  cmd->add_option("--camera", o->camera, "camera of the scene (default: its first)");
  cmd->add_option("--size", o->size, "render size WxH")->capture_default_str();
  cmd->add_option("--display", o->display, "display W_CM,H_CM,DIST_CM[,RES_X,RES_Y]: the recording's screen fills it")
      ->capture_default_str();
  cmd->add_option("--max-rays", o->max_rays, "n_max (the fovea's rays and the reference's)")->capture_default_str();
  cmd->add_option("--tolerance", o->tolerance,
                  "the deadline loops' τ(E) scale: a pixel stops once its standard error is within it (as render --tolerance)")
      ->capture_default_str()
      ->check(positive());
  cmd->add_option("--seed", o->seed, "seed of the loops (the references use seed+1000 and seed+2000)")->capture_default_str();
  cmd->add_option("--refresh-hz", o->refresh_hz, "display refresh rate, Hz")->capture_default_str()->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--frame-budget-ms", o->budget_ms, "each frame's budget, ms (default: one refresh)");
  add_loop_options(*cmd, o->loop, "the deadline loops: ");
  cmd->add_option("--latency-ms", o->latency_ms,
                  "tracker latency: a sample reaches the renderer this long after it was taken (default: "
                  "the sample period + 2 ms)");
  cmd->add_option("--clock", o->clock,
                  "wall: each frame costs its measured time; model: a cost model calibrated at the start (reproducible runs)")
      ->capture_default_str();
  cmd->add_option("--model-rays-per-ms", o->model_rays_per_ms,
                  "--clock model: the cost model's AO rays per ms (with --model-fixed-ms; default: measured on the view first)");
  cmd->add_option("--model-fixed-ms", o->model_fixed_ms, "--clock model: each frame's cost besides its AO rays, ms");
  cmd->add_option("--loops", o->loops,
                  "loops to run, comma-separated: whole-frame, deadline, deadline+prediction; also deadline+oracle (a perfect predictor: "
                  "each saccade's true landing from its detected onset, the most prediction could gain)")
      ->capture_default_str();
  add_landing_option(*cmd, o->landing, "the prediction loops: ");
  cmd->add_option("--min-amplitude", o->min_amplitude, "saccades smaller than this are not judged, degrees")->capture_default_str();
  cmd->add_option("--threads", o->threads, "worker threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
  add_device_option(*cmd, o->device);
  cmd->add_option("--json", o->json, "write every figure as JSON")->check(output_file());
  cmd->add_option("--markdown", o->markdown, "write the tables as Markdown")->check(output_file());
  cmd->add_option("--timeline", o->timeline, "draw one saccade's timeline (gaze, fovea placement, fovea error per frame): .png or .svg")
      ->check(output_file(plot_extensions()));
  cmd->add_option("--timeline-saccade", o->timeline_saccade,
                  "which saccade of the first recording --timeline draws (0 = the first; where its fovea was ready at its landing, the "
                  "bench names the one the deadline loop waited longest for)")
      ->capture_default_str()
      ->check(non_negative());
  return [o] { return run_bench_latency(*o); };
}

}  // namespace foveal::app
