// apps/bench_quality.cpp — `foveal bench quality`: the speed–quality trade-off of the foveation
// model's parameters (γ, n_max, β), with the Pareto front and the configuration it recommends.
#include "commands.h"
#include "foveal/io/plot.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/render/outputs.h"
#include "foveal/experiments/sequence.h"
#include "foveal/experiments/sweep.h"
#include "foveal/experiments/ao_benchmark.h"
#include "foveal/experiments/replay.h"
#include "foveal/trace/tracer.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/util/text.h"

#include <fmt/core.h>

#include <memory>

namespace foveal::app {

namespace {

// The gaze a replay of the recording renders at each of `frames` frames (the fixation filter's
// output, the image centre before the first fixation), without rendering them.
std::vector<glm::dvec2> recording_gaze_path(const std::string& path, const RenderParams& params, double start_s, double fps, int frames) {
  const Recording recording = read_recording_warned(path, ReadOptions{});
  ReplaySettings settings;
  settings.fps = fps;
  settings.frames = frames;
  settings.start_s = start_s;
  if (start_s > recording.duration_s()) fail("--start: {} s is past the end of {} ({:.3f} s long)", start_s, path, recording.duration_s());
  std::vector<glm::dvec2> gazes;
  for (const ReplayFrame& f : replay_gazes(recording, params.display, params, settings)) gazes.push_back(f.render_gaze);
  return gazes;
}

// The command's options as typed.
struct BenchQualityOptions {
  std::string scene, camera, size = "840x525", display = "47.5,30,60,1680,1050", ambient = "1", json, markdown, plot;
  std::string gamma = "1,2,3,4", max_rays = "100,200,400", beta = "0,0.5,1,2", gaze_names = "object,centre";
  std::string configs = "paper,adaptive+denoise";
  std::vector<std::string> gazes;
  int reference_rays = 400, threads = 0, repeats = 1;
  double ellipse = 1.538, max_error = 4, max_flicker = 2, saccade = 5, tolerance = AoReuseParams{}.tolerance,
         denoise_radius = AoReuseParams{}.denoise_radius;
  uint64_t seed = 1;
  bool full = false;
  bool sequence = false;
  std::string device = "cpu";
  int frames = 24, fixation_frames = 6;
  double orbit = 3;
  std::string recording;
  double start = 0, fps = 30;
  // Which lists were given (the full grid and --sequence replace only the defaults)
  bool gamma_given = false, max_rays_given = false, beta_given = false, gaze_names_given = false, configs_given = false;
};

// --full: the full grid replaces the quick one's defaults, not values the user gave.
void apply_full_grid(BenchQualityOptions& o) {
  if (!o.gamma_given) o.gamma = "1,1.5,2,2.5,3,4";
  if (!o.max_rays_given) o.max_rays = "50,100,200,300,400";
  if (!o.beta_given) o.beta = "0,0.25,0.5,1,2,4";
  if (!o.gaze_names_given) o.gaze_names = "all";
  if (!o.configs_given) o.configs = "paper,adaptive,denoise,adaptive+denoise";
  o.repeats = std::max(o.repeats, 3);
}

// The methods, and the options that need no scene, checked before it loads.
std::vector<ReuseConfig> quality_methods(BenchQualityOptions& o, ComputeDevice device) {
  if (!o.sequence && !o.recording.empty()) fail("--recording: only with --sequence");
  if (!o.sequence && device == ComputeDevice::cuda)
    fail("--device {}: the single-frame sweep runs on the CPU; the GPU measures --sequence", o.device);
  if (o.sequence && !o.configs_given) o.configs = "paper,adaptive+denoise,temporal,temporal+adaptive,temporal+adaptive+denoise";
  std::vector<ReuseConfig> methods = parse_reuse_configs("--configs", o.configs);
  for (ReuseConfig& m : methods) m.reuse.tolerance = o.tolerance, m.reuse.denoise_radius = o.denoise_radius;
  if (!o.sequence)
    for (const ReuseConfig& m : methods)
      if (m.reuse.temporal) fail("--configs: {} reuses earlier frames, a single frame has none (add --sequence)", m.name);
  return methods;
}

// The sweep's grid and render parameters; `camera` is the one the options name.
QualitySweepParams sweep_params(const BenchQualityOptions& o, const Scene& scene, const std::string& spec, Camera& camera) {
  ViewOptions view;
  view.scene = spec;
  view.camera = o.camera;
  view.size = o.size;
  view.display = o.display;
  RenderOptions ro;
  ro.ambient = o.ambient;
  ro.ellipse = o.ellipse;
  QualitySweepParams p;
  p.render = resolve_render_params(view, ro);
  camera = resolve_camera(scene, view);
  p.camera_name = o.camera.empty() ? (scene.cameras.empty() ? std::string("default") : scene.cameras.front().name) : o.camera;
  p.gammas = parse_numbers("--gamma", o.gamma);
  p.betas = parse_numbers("--beta", o.beta);
  p.max_rays.clear();
  for (double n : parse_numbers("--max-rays", o.max_rays)) {
    if (n != std::floor(n) || n < 1 || n > 65535) fail("--max-rays: every value must be a whole number in [1, 65535], got {:g}", n);
    p.max_rays.push_back(static_cast<int>(n));
  }
  p.reference_rays = o.reference_rays;
  p.seed = o.seed;
  p.repeats = o.repeats;
  p.saccade_deg = o.saccade;
  return p;
}

// The gaze points: given (--gaze), or named points of the first paper's table found on a primary-ray frame.
std::vector<std::pair<std::string, glm::dvec2>> quality_gazes(const BenchQualityOptions& o, const Scene& scene, const Tracer& tracer,
                                                              const Camera& camera, const RenderParams& render) {
  std::vector<std::pair<std::string, glm::dvec2>> gazes;
  if (!o.gazes.empty()) {
    for (const std::string& g : o.gazes) gazes.emplace_back(g, parse_vec2("--gaze", g));
    return gazes;
  }
  RenderParams probe = render;
  probe.foveation.max_rays = 0;
  const auto named = benchmark_gazes(scene, render_frame(tracer, scene, camera, probe));
  for (const std::string_view name : text::split(o.gaze_names, ',')) {
    bool found = false;
    for (const auto& g : named)
      if (name == "all" || g.first == name) gazes.push_back(g), found = true;
    if (!found) fail("--gazes: unknown gaze point '{}' (object, centre, top-left, top-right, bottom-left, bottom-right or all)", name);
  }
  return gazes;
}

void print_line(const std::string& line) {
  fmt::print("  {}\n", line);
  std::fflush(stdout);
}

// --sequence: the configurations over a camera orbit and a moving gaze, every frame on `device`.
int run_sequence(const BenchQualityOptions& o, const Scene& scene, const Tracer& tracer, const Camera& camera, const std::string& spec,
                 const QualitySweepParams& p, const std::vector<ReuseConfig>& methods, ComputeDevice device, int threads) {
  QualitySequenceParams q;
  q.render = p.render;
  q.reference_rays = o.reference_rays;
  q.seed = o.seed;
  q.cameras = orbit_path(camera, o.orbit, o.frames);
  q.configs = methods;
  std::string gaze_text;
  if (o.recording.empty()) {
    q.gazes = fixation_path(p.gazes.front().second, p.render, o.frames, o.fixation_frames);
    gaze_text = fmt::format("gaze around {} at {:.0f},{:.0f} (a fixation every {} frames)", p.gazes.front().first, p.gazes.front().second.x,
                            p.gazes.front().second.y, o.fixation_frames);
  } else {
    q.gazes = recording_gaze_path(o.recording, p.render, o.start, o.fps, o.frames);
    gaze_text = fmt::format("gaze of {} from {:g} s at {:g} fps", o.recording, o.start, o.fps);
  }
  fmt::print("foveal bench quality --sequence: {} ({} triangles), camera {} orbiting {:g}° over {} frames, {}, {}x{}, {}\n", spec,
             tracer.triangles(), p.camera_name, o.orbit, o.frames, gaze_text, p.render.width, p.render.height,
             device == ComputeDevice::cuda ? "device " + describe_device(device) : fmt::format("{} threads", threads));
  // Every frame, the references too, on the chosen device (the CPU's shares the tracer)
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(scene, device, tracer);
  const QualitySequenceResult result = run_quality_sequence(scene, *renderer, q, print_line);
  const std::string table = to_markdown(result);
  fmt::print("\n{}\n", table);
  if (!o.json.empty()) write_json_file(o.json, to_json(result));
  if (!o.markdown.empty()) write_text_file(o.markdown, table);
  const FoveationParams& f = p.render.foveation;
  if (!o.plot.empty()) write_pareto_plot(sequence_points(result, f), o.plot, f.gamma, f.max_rays, f.beta);
  return 0;
}

// The single-frame sweep with its Pareto front and the recommended configuration.
int run_sweep(const BenchQualityOptions& o, const Scene& scene, const Tracer& tracer, const Camera& camera, const std::string& spec,
              const QualitySweepParams& p, int threads) {
  fmt::print(
      "foveal bench quality: {} ({} triangles), camera {}, {}x{}, {} threads; {} gamma × {} n_max × {} method(s) × {} beta at {} gaze "
      "point(s)\n",
      spec, tracer.triangles(), p.camera_name, p.render.width, p.render.height, threads, p.gammas.size(), p.max_rays.size(),
      p.methods.size(), p.betas.size(), p.gazes.size());
  for (const auto& [label, g] : p.gazes) fmt::print("  gaze {} at {:.0f},{:.0f}\n", label, g.x, g.y);
  const QualitySweepResult result = run_quality_sweep(scene, tracer, camera, p, print_line);
  const std::string table = to_markdown(result);
  fmt::print("\n{}\n", table);
  const FoveationParams defaults;
  const int pick = recommended_point(result.points, o.max_error, o.max_flicker);
  const std::string rule = fmt::format("fastest with the fovea within noise, acuity-weighted error ≤ {:g}× and flicker ≤ {:g}× noise",
                                       o.max_error, o.max_flicker);
  if (pick >= 0) {
    const QualityPoint& q = result.points[pick];
    fmt::print("recommended ({}): {}, gamma {:g}, n_max {}, beta {:g} — {:.2f}× faster, error {:.2f}×, flicker {:.2f}× noise\n", rule,
               q.method, q.gamma, q.max_rays, q.beta, q.speedup, q.weighted_ratio, q.flicker_ratio);
  } else {
    fmt::print("recommended: none ({})\n", rule);
  }
  for (const QualityPoint& q : result.points)
    if (q.gamma == defaults.gamma && q.max_rays == defaults.max_rays && q.beta == defaults.beta)
      fmt::print(
          "{} at the defaults (gamma {:g}, n_max {}, beta {:g}): {:.2f}× faster, error {:.2f}×, flicker {:.2f}× noise, fovea {}, {}\n",
          q.method, q.gamma, q.max_rays, q.beta, q.speedup, q.weighted_ratio, q.flicker_ratio,
          q.fovea_within_noise ? "within noise" : "outside noise", q.pareto ? "on the Pareto front" : "not on the Pareto front");
  if (!o.json.empty()) {
    auto j = to_json(result);
    j["repeats"] = p.repeats;
    j["max_error"] = o.max_error;
    j["max_flicker"] = o.max_flicker;
    j["recommended"] = pick;
    write_json_file(o.json, j);
  }
  if (!o.markdown.empty()) write_text_file(o.markdown, table);
  if (!o.plot.empty()) write_pareto_plot(result, o.plot, defaults.gamma, defaults.max_rays, defaults.beta);
  return 0;
}

int run_bench_quality(BenchQualityOptions& o) {
  const ThreadScope threads(o.threads);
  if (o.full) apply_full_grid(o);
  const ComputeDevice device = choose_device(o.device);
  const std::vector<ReuseConfig> methods = quality_methods(o, device);
  std::string spec = o.scene;
  const Scene scene = load_paper_scene(spec, "bench quality");
  Camera camera;
  QualitySweepParams p = sweep_params(o, scene, spec, camera);
  const Tracer tracer(scene);
  p.gazes = quality_gazes(o, scene, tracer, camera, p.render);
  if (o.sequence) return run_sequence(o, scene, tracer, camera, spec, p, methods, device, threads.threads());
  p.methods = methods;
  return run_sweep(o, scene, tracer, camera, spec, p, threads.threads());
}

}  // namespace

std::function<int()> add_bench_quality_command(CLI::App& bench) {
  auto* cmd = bench.add_subcommand(
      "quality",
      "speed–quality trade-off: sweeps γ, n_max, β and the methods (the paper's, adaptive rays, denoising; temporal "
      "reuse with --sequence), times each against the full frame, measures its error per band, and draws the Pareto front");

  auto o = std::make_shared<BenchQualityOptions>();
  cmd->add_option("--scene", o->scene,
                  "scene (default: scenes/dragon-box.json, the paper's dragon in a box; builtin:box when the dragon is absent)");
  cmd->add_option("--camera", o->camera, "camera of the scene (default: its first)");
  cmd->add_option("--size", o->size, "render size WxH")->capture_default_str();
  cmd->add_option("--display", o->display, "display W_CM,H_CM,DIST_CM[,RES_X,RES_Y]")->capture_default_str();
  auto* gamma = cmd->add_option("--gamma", o->gamma, "γ values to sweep, comma-separated")->capture_default_str();
  auto* max_rays = cmd->add_option("--max-rays", o->max_rays, "n_max values to sweep, comma-separated")->capture_default_str();
  auto* beta = cmd->add_option("--beta", o->beta, "β values to sweep, comma-separated")->capture_default_str();
  auto* configs =
      cmd->add_option("--configs", o->configs,
                      "methods, comma-separated: paper (the paper's), or adaptive, denoise, temporal joined by '+' (temporal only "
                      "with --sequence; --sequence's default: paper,adaptive+denoise,temporal,temporal+adaptive,temporal+adaptive+denoise; "
                      "--full's: paper,adaptive,denoise,adaptive+denoise)")
          ->capture_default_str();
  cmd->add_option("--tolerance", o->tolerance, "every method's τ(E) scale (adaptive rays and denoising; as render --tolerance)")
      ->capture_default_str()
      ->check(positive());
  cmd->add_option("--denoise-radius", o->denoise_radius, "every method's filter footprint factor (as render --denoise-radius)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  auto* gaze_names =
      cmd->add_option("--gazes", o->gaze_names,
                      "gaze points by name, comma-separated: object (the pixel nearest the object's centroid), centre, top-left, "
                      "top-right, bottom-left, bottom-right, or all")
          ->capture_default_str();
  cmd->add_option("--gaze", o->gazes, "an explicit gaze point X,Y in render pixels (repeatable; replaces --gazes)");
  cmd->add_option("--reference-rays", o->reference_rays, "rays per pixel of the full-frame reference")
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  cmd->add_option("--ellipse", o->ellipse, "horizontal:vertical ratio a of the elliptical ROI")->capture_default_str();
  cmd->add_option("--ambient-constant", o->ambient, "k_const away from the gaze: a number, or auto (mean AO visibility of the fovea)")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "seed of the foveated frames (the references use seed+1 and seed+2)")->capture_default_str();
  cmd->add_option("--repeats", o->repeats, "timed frames per configuration (median)")->capture_default_str()->check(CLI::Range(1, 100));
  cmd->add_option("--max-error", o->max_error,
                  "the recommendation: the fastest configuration whose fovea is within the reference's noise and whose "
                  "acuity-weighted error is at most this many times the reference's noise")
      ->capture_default_str()
      ->check(positive());
  cmd->add_option("--max-flicker", o->max_flicker, "… and whose flicker after a saccade is at most this many times the reference's noise")
      ->capture_default_str()
      ->check(positive());
  cmd->add_option("--saccade", o->saccade, "flicker: the saccade between the two frames compared, degrees (horizontal)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 90.0));
  cmd->add_flag("--full", o->full,
                "full run: γ 1,1.5,2,2.5,3,4 × n_max 50,100,200,300,400 × β 0,0.25,0.5,1,2,4 × four methods at all six gaze "
                "points, 3 frames each (default: a quick grid at two gaze points)");
  cmd->add_option("--threads", o->threads, "worker threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
  cmd->add_option("--json", o->json, "write every configuration, gaze point and band as JSON")->check(output_file());
  cmd->add_option("--markdown", o->markdown, "write the table as Markdown")->check(output_file());
  cmd->add_option(
         "--plot", o->plot,
         "the Pareto plot: speed-up against the acuity-weighted error and the flicker (.png or .svg; with --sequence, its configurations)")
      ->check(output_file(plot_extensions()));
  cmd->add_flag("--sequence", o->sequence,
                "sequence mode: the paper's method, adaptive+denoise and temporal reuse (alone, +adaptive, +denoise) along a camera "
                "orbit with the gaze fixating around the first gaze point (--gazes object), each frame judged against the reference "
                "at its camera");
  cmd->add_option("--device", o->device,
                  "--sequence: where every frame, the references too, is rendered: cpu, cuda (the GPU renderer; refused with "
                  "the reason where there is none) or auto (the GPU where one is usable); the single-frame sweep runs on the CPU")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "--sequence: frames")->capture_default_str()->check(CLI::Range(2, 100000));
  cmd->add_option("--orbit", o->orbit, "--sequence: the camera's orbit about the look point over the frames, degrees")
      ->capture_default_str()
      ->check(CLI::Range(-360.0, 360.0));
  cmd->add_option("--fixation-frames", o->fixation_frames, "--sequence: frames per fixation (a 1° saccade between them)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--recording", o->recording,
                  "--sequence: the gaze of a recording (EyeLink .asc, Pupil gaze_positions.csv, Tobii .tsv, t,x,y CSV) instead of "
                  "the synthetic fixations, as `replay` follows it: the causal fixation filter's output at each frame, the "
                  "recording's screen mapped onto the render");
  cmd->add_option("--start", o->start, "--recording: start this many seconds after its first sample")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e9));
  cmd->add_option("--fps", o->fps, "--recording: frames per second of gaze time")->capture_default_str()->check(CLI::Range(0.1, 10000.0));

  return [o, gamma, max_rays, beta, gaze_names, configs] {
    o->gamma_given = gamma->count() > 0;
    o->max_rays_given = max_rays->count() > 0;
    o->beta_given = beta->count() > 0;
    o->gaze_names_given = gaze_names->count() > 0;
    o->configs_given = configs->count() > 0;
    return run_bench_quality(*o);
  };
}

}  // namespace foveal::app
