// apps/simulate_command.cpp — `foveal simulate`: the second paper's temporal simulation of vision.
#include "commands.h"

#include "foveal/gaze/steps.h"
#include "foveal/io/image_io.h"
#include "foveal/render/outputs.h"
#include "foveal/io/scanpath.h"
#include "foveal/io/video.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/impair/profile.h"
#include "foveal/util/files.h"
#include "foveal/util/stats.h"
#include "foveal/util/timer.h"
#include "foveal/vision/simulate.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <unistd.h>

namespace foveal::app {

namespace {

// The command's options as typed.
struct SimulateOptions {
  ViewOptions view;
  GazeOptions gaze;
  std::string gaze_source, gaze_display = "47.5,30,60", stimulus;
  double start = 0, live_timeout = 5;
  bool no_gaze_blinks = false;
  std::string eye = "healthy", save_steps = "1,4,20", output, stats, video, path;
  int steps = 20, fast_threshold = 20, blink_every = 0, taps = 64;
  std::optional<double> pupil, image_distance;  // not given: the profile's or presets', else the default
  double starvation = 0.015, voxel = 0, saccade_max = 15, saccade_min = 2, ambient = 0.3;
  uint64_t seed = 1;
  bool quiet = false;
  std::string device = "auto";
  bool steps_given = false;  // --steps was on the command line (else a recording gives every fixation)
};

// Options → the simulation's parameters, all checked before any work.
SimulateParams simulate_params(const SimulateOptions& o, ComputeDevice device) {
  SimulateParams p;
  p.cuda = device == ComputeDevice::cuda;
  const glm::ivec2 size = parse_size("--size", o.view.size);
  p.width = size.x;
  p.height = size.y;
  const EyeSpec eye_spec = resolve_eye(o.eye, {o.pupil, o.image_distance});
  p.eye = eye_spec.eye;
  p.impair = eye_spec.impair;
  p.starvation = o.starvation;
  p.voxel = static_cast<float>(o.voxel);
  if (o.voxel < 0) fail("--voxel: must be zero (automatic) or positive, got {}", o.voxel);
  p.blink_every = o.blink_every;
  p.fast_threshold = o.fast_threshold;
  p.saccades.max_amplitude_deg = o.saccade_max;
  p.saccades.min_distance_deg = o.saccade_min;
  p.blur.taps = o.taps;
  p.ambient = static_cast<float>(o.ambient);
  p.seed = o.seed;
  validate(p);
  return p;
}

// --save-steps: the steps whose perceived image is saved (`all`: every step).
struct SavedSteps {
  bool all = false;
  std::set<int> steps;
  bool operator()(int k) const { return all || steps.count(k); }
  bool any() const { return all || !steps.empty(); }
};
SavedSteps saved_steps(const std::string& text) {
  SavedSteps save;
  save.all = text == "all";
  if (!save.all && !text.empty())
    for (double v : parse_numbers("--save-steps", text)) {
      if (v < 1 || v != std::floor(v)) fail("--save-steps: steps are whole numbers from 1, got {}", v);
      save.steps.insert(static_cast<int>(v));
    }
  return save;
}

// Real gaze (--gaze): the fixations of a recording, or a live tracker's, mapped into render pixels.
struct GazeSteps {
  bool live = false;
  std::optional<GazeGeometry> geometry;
  std::optional<ScreenMapping> mapping;
  std::vector<GazeStep> recorded;
  std::unique_ptr<PupilSource> tracker;
  std::unique_ptr<LiveSteps> steps;
  std::string summary;
  // The next step's fixation (nullopt: the live tracker stopped, `why` says why)
  std::optional<GazeStep> next(int k, double timeout_s, std::string& why) {
    if (!steps) return recorded[size_t(k - 1)];
    std::optional<GazeStep> g = steps->next(timeout_s);
    if (!g) why = steps->why();
    return g;
  }
};

// Opens --gaze; for a recording `step_count` becomes its fixation count unless --steps asked for fewer.
std::unique_ptr<GazeSteps> open_gaze(const SimulateOptions& o, const SimulateParams& p, int& step_count) {
  auto g = std::make_unique<GazeSteps>();
  g->live = o.gaze_source.rfind("pupil://", 0) == 0;
  if (!g->live && o.gaze_source.find("://") != std::string::npos)
    fail("--gaze: unknown live source '{}' (live trackers: pupil://HOST:PORT[?surface=NAME])", o.gaze_source);
  const StepFixations from = parse_step_fixations(o.gaze.fixation);
  // A live tracker's causal filter, decided before connecting (`tracker` is refused); unused for recordings
  const FixationMethod live_method = g->live ? live_filter(from) : FixationMethod::ivt;
  if (!(o.start >= 0) || !std::isfinite(o.start)) fail("--start: must be zero or positive seconds, got {}", o.start);
  if (!(o.live_timeout > 0)) fail("--live-timeout: must be positive seconds, got {}", o.live_timeout);
  const Display display = parse_display(o.gaze_display, Display{});
  const ReadOptions read = resolve_read_options(o.gaze, display);
  const FixationParams fixation = resolve_fixation_params(o.gaze);
  if (g->live) {
    g->tracker = std::make_unique<PupilSource>(o.gaze_source, read.screen_px, read.min_confidence);
    g->geometry.emplace(display, g->tracker->screen_px());
    g->steps = std::make_unique<LiveSteps>(*g->tracker, live_method, fixation, *g->geometry);
    g->summary = fmt::format("live {} ({} filter)", o.gaze_source, to_string(from));
  } else {
    const Recording recording = read_recording_warned(o.gaze_source, read);
    if (recording.samples.empty()) fail("{}: no samples", recording.source);
    g->geometry.emplace(display, recording.screen_px);
    const double t0 = recording.samples.front().t_s + o.start;
    for (const GazeStep& step : recording_steps(recording, *g->geometry, from, fixation))
      if (step.start_s >= t0) g->recorded.push_back(step);
    if (g->recorded.empty())
      fail("{}: no fixations{} ({} filter)", recording.source, o.start > 0 ? fmt::format(" after --start {} s", o.start) : "",
           to_string(from));
    // Every fixation unless --steps asks for fewer
    if (!o.steps_given || step_count > int(g->recorded.size())) step_count = static_cast<int>(g->recorded.size());
    const auto blinks =
        std::count_if(g->recorded.begin(), g->recorded.begin() + step_count, [](const GazeStep& s) { return s.blink_before; });
    g->summary = fmt::format("{} ({} fixations by {}, {} blinks{})", recording.source, g->recorded.size(), to_string(from),
                             o.no_gaze_blinks ? 0 : blinks, o.no_gaze_blinks ? " ignored" : "");
  }
  g->mapping = make_screen_mapping(g->geometry->screen_px(), {p.width, p.height}, o.stimulus);
  return g;
}

// What the steps gave.
struct SimulateRun {
  std::vector<StepStats> steps;
  std::vector<glm::vec2> fixations;
  std::vector<GazeStep> gaze_steps;
  std::string stopped;  // why a live tracker stopped the run early
  double path_px() const {
    double px = 0;
    for (size_t k = 1; k < fixations.size(); ++k) px += glm::length(fixations[k] - fixations[k - 1]);
    return px;
  }
  // The median over steps of a stage's time (of the impairments' with `impair`)
  double median_ms(double StepStats::*field) const {
    std::vector<double> v;
    for (const StepStats& s : steps) v.push_back(s.*field);
    return median(v);
  }
  double median_ms(double ImpairTimes::*field) const {
    std::vector<double> v;
    for (const StepStats& s : steps) v.push_back(s.impair.*field);
    return median(v);
  }
};

// The steps, each saved as asked, with a progress line on a terminal.
SimulateRun run_steps(const SimulateOptions& o, VisionSimulation& sim, const Camera& camera, const CameraPath* path, GazeSteps* gaze,
                      int step_count, const SavedSteps& save, const std::filesystem::path& dir) {
  const bool show = !o.quiet && isatty(fileno(stderr));
  const Timer clock;
  SimulateRun run;
  for (int k = 1; k <= step_count; ++k) {
    std::optional<glm::vec2> fixation;
    if (gaze) {
      const std::optional<GazeStep> g = gaze->next(k, o.live_timeout, run.stopped);
      if (!g) break;
      if (g->blink_before && !o.no_gaze_blinks) sim.blink_before_next_step();
      fixation = glm::vec2(gaze->mapping->to_render(g->screen_px));
      run.gaze_steps.push_back(*g);
    }
    const StepStats s = sim.step(path ? path->at(k) : camera, fixation);
    run.steps.push_back(s);
    run.fixations.push_back(s.focus_px);
    if (save(k)) save_image(sim.perceived(), (dir / fmt::format("step_{:04d}.png", k)).string());
    if (!o.video.empty()) save_image(sim.perceived(), (dir / fmt::format("frame_{:05d}.png", k - 1)).string());
    if (show && clock.ms() > 1000)
      fmt::print(stderr, "\r  step {}/{}  sharp {:.1f}%  {:.0f} ms/step ", k, step_count, 100 * s.sharp_fraction, s.total_ms);
  }
  if (show && clock.ms() > 1000) fmt::print(stderr, "\r{:70}\r", "");
  if (run.steps.empty()) fail("{}", run.stopped);
  return run;
}

// The last step's images, the scan path and the video.
void write_pictures(const SimulateOptions& o, const VisionSimulation& sim, const SimulateRun& run, const std::filesystem::path& dir) {
  save_image(sim.color(), (dir / "sharp.png").string());
  save_image(sim.perceived(), (dir / "perceived.png").string());
  std::vector<glm::vec2> corner_points;
  for (const Corner& c : sim.corners()) corner_points.push_back(c.px);
  write_fixation_picture(sim.color(), run.fixations, corner_points, (dir / "scanpath.png").string());
  if (!o.video.empty()) encode_video((dir / "frame_%05d.png").string(), 10, o.video);
}

// --stats: the run, the eye, the field, median stage times and every step.
nlohmann::json simulate_stats_json(const SimulateOptions& o, const SimulateParams& p, const Scene& scene, const Tracer& tracer,
                                   const VisionSimulation& sim, const SimulateRun& run, int threads, ComputeDevice device, bool live) {
  nlohmann::json j;
  j["width"] = p.width;
  j["height"] = p.height;
  j["eye"] = o.eye;
  j["optics"] = optics_json(p.eye);
  j["impairments"] = p.impair.describe();
  j["seed"] = p.seed;
  j["threads"] = threads;
  j["device"] = to_string(device);
  j["scene"] = {{"source", scene.source}, {"triangles", tracer.triangles()}, {"build_ms", tracer.build_ms()}};
  j["pixels_per_degree"] = sim.pixels_per_degree();
  j["field"] = {{"voxel", sim.field().voxel()}, {"cells", sim.field().cells()}, {"starvation", p.starvation}};
  j["time_ms"] = {{"trace", run.median_ms(&StepStats::trace_ms)},         {"features", run.median_ms(&StepStats::features_ms)},
                  {"sharpness", run.median_ms(&StepStats::sharpness_ms)}, {"blur", run.median_ms(&StepStats::blur_ms)},
                  {"impairments", run.median_ms(&ImpairTimes::total_ms)}, {"media", run.median_ms(&ImpairTimes::media_ms)},
                  {"retina", run.median_ms(&ImpairTimes::field_ms)},      {"colour", run.median_ms(&ImpairTimes::colour_ms)},
                  {"total", run.median_ms(&StepStats::total_ms)},         {"statistic", "median over steps"}};
  j["scan_path_px"] = run.path_px();
  const bool gaze = !o.gaze_source.empty();
  if (gaze) j["gaze"] = {{"source", o.gaze_source}, {"live", live}, {"fixation", o.gaze.fixation}, {"stopped", run.stopped}};
  for (const StepStats& s : run.steps) {
    j["steps"].push_back(step_stats_json(s));
    if (gaze) {
      const GazeStep& g = run.gaze_steps[size_t(s.step - 1)];
      j["steps"].back()["gaze"] = {{"t_s", g.start_s},
                                   {"duration_s", g.duration_s},
                                   {"screen_px", {g.screen_px.x, g.screen_px.y}},
                                   {"blink_before", g.blink_before}};
    }
  }
  return j;
}

// The summary on stdout.
void print_summary(const SimulateOptions& o, const SimulateParams& p, const Scene& scene, const Tracer& tracer, const Camera& camera,
                   const CameraPath* path, const SimulateRun& run, int threads, ComputeDevice device, const GazeSteps* gaze,
                   const SavedSteps& save) {
  const FocusRange range = focus_range(p.eye);
  fmt::print("foveal simulate: {} ({} triangles), camera '{}', {}x{}, eye {} (focus {:.2f} m … {}), {} steps, {} threads\n", scene.source,
             tracer.triangles(), path ? "path " + path->name : camera.name, p.width, p.height, o.eye, range.near_point_m(),
             std::isfinite(range.far_point_m()) ? fmt::format("{:.2f} m", range.far_point_m()) : "infinity", run.steps.size(), threads);
  fmt::print("  device   {}\n", describe_device(device));
  if (p.impair.any())
    fmt::print("  impaired {} ({:.1f} ms per step; on the CPU{})\n", p.impair.describe(), run.median_ms(&ImpairTimes::total_ms),
               p.cuda ? ", after the GPU's passes" : "");
  if (gaze) fmt::print("  gaze     {}\n", gaze->summary);
  fmt::print("  sharp    {:.1f}% of the image after the last step; scan path {:.0f} px over {} fixations\n",
             100 * run.steps.back().sharp_fraction, run.path_px(), run.fixations.size());
  fmt::print("  time     per step (median): trace {:.1f} ms, features {:.1f} ms, sharpness {:.1f} ms, blur {:.1f} ms, total {:.1f} ms\n",
             run.median_ms(&StepStats::trace_ms), run.median_ms(&StepStats::features_ms), run.median_ms(&StepStats::sharpness_ms),
             run.median_ms(&StepStats::blur_ms), run.median_ms(&StepStats::total_ms));
  fmt::print("  wrote    {}/perceived.png, sharp.png, scanpath.png{}{}\n", o.output, save.any() ? ", step_NNNN.png" : "",
             o.stats.empty() ? "" : ", " + o.stats);
}

int run_simulate(const SimulateOptions& o) {
  const ThreadScope threads(o.view.threads);
  for (const auto& [option, path] : {std::pair{"--stats", &o.stats}, std::pair{"--video", &o.video}})
    check_output_beside_folder(option, *path, o.output, [](const std::string& name) {
      return name == "sharp.png" || name == "perceived.png" || name == "scanpath.png" ||
             ((name.rfind("step_", 0) == 0 || name.rfind("frame_", 0) == 0) && lower_extension(name) == ".png");
    });
  resolve_fixation_params(o.gaze);  // the fixation filter's options are checked without --gaze too
  const ComputeDevice device = choose_device(o.device);
  const SimulateParams p = simulate_params(o, device);
  const SavedSteps save = saved_steps(o.save_steps);
  int step_count = o.steps;
  std::unique_ptr<GazeSteps> gaze;
  if (!o.gaze_source.empty()) gaze = open_gaze(o, p, step_count);

  const Scene scene = load_scene(o.view.scene);
  const Camera camera = resolve_camera(scene, o.view);
  const CameraPath* path = o.path.empty() ? nullptr : &find_camera_path(scene, o.path);
  const Tracer tracer(scene);
  VisionSimulation sim(tracer, scene, p);
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(o.output, ec);
  if (ec) fail("{}: cannot create the output folder: {}", o.output, ec.message());
  const fs::path dir(o.output);

  const SimulateRun run = run_steps(o, sim, camera, path, gaze.get(), step_count, save, dir);
  write_pictures(o, sim, run, dir);
  if (!o.stats.empty())
    write_json_file(o.stats, simulate_stats_json(o, p, scene, tracer, sim, run, threads.threads(), device, gaze && gaze->live));
  // A live tracker that went away: everything so far is written; say why it stopped
  if (!run.stopped.empty()) fail("{} (stopped after {} steps; the outputs so far are written)", run.stopped, run.steps.size());
  if (!o.quiet) print_summary(o, p, scene, tracer, camera, path, run, threads.threads(), device, gaze.get(), save);
  return 0;
}

}  // namespace

std::function<int()> add_simulate_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "simulate", "simulate human vision over time: fixations, accommodation, a sharpness field that remembers, variable blur");

  auto o = std::make_shared<SimulateOptions>();
  o->view.size = "1024x768";
  o->view.eye_option = "--from";
  o->view.display_option = false;
  add_view_options(*cmd, o->view);
  cmd->add_option("--path", o->path, "a camera path of the scene JSON (camera_paths): the camera moves between steps");
  auto* steps_option =
      cmd->add_option("--steps", o->steps,
                      "time steps (one fixation each); with a --gaze recording: at most this many (default: all its fixations)")
          ->capture_default_str()
          ->check(CLI::Range(1, 100000));
  cmd->add_option("--eye", o->eye,
                  "eye: healthy, glaucoma[:SEVERITY 0..1], myopia:-D, hyperopia:D, presbyopia:AGE, astigmatism:CYL[@AXIS], "
                  "age:Y, cataract[:S], glare, cvd:TYPE[:S], achromatopsia, field:FILE.csv|GRID:FILE|DEFECT, field-view:OD|OS|both, "
                  "field-mode:contrast|blur|grey|fill, amd[:R[:A]], metamorphopsia:A[:R]; join with '+'; or a profile .json")
      ->capture_default_str();
  cmd->add_option("--pupil", o->pupil, "pupil diameter A, mm (overrides a profile's pupil_mm; default: the profile's, else 3.5)");
  cmd->add_option("--image-distance", o->image_distance, "lens-to-retina distance I, mm (default 25)");
  cmd->add_option("--starvation", o->starvation, "s: remembered CoCs grow by this fraction per step")->capture_default_str();
  cmd->add_option("--voxel", o->voxel, "sharpness-field cell edge, scene units (0: scene diagonal / 256)")->capture_default_str();
  cmd->add_option("--blink-every", o->blink_every, "a blink (the field forgets) every N steps; 0 = never")->capture_default_str();
  cmd->add_option("--fast-threshold", o->fast_threshold, "FAST-9 threshold (OpenCV's cv::FAST)")->capture_default_str();
  cmd->add_option("--saccade-max", o->saccade_max, "largest saccade, degrees (glaucoma shortens it)")->capture_default_str();
  cmd->add_option("--saccade-min", o->saccade_min, "smallest distance to the recent fixations, degrees")->capture_default_str();
  cmd->add_option("--blur-taps", o->taps, "most taps of the variable blur per pixel (large CoCs)")->capture_default_str();
  cmd->add_option("--ambient", o->ambient, "constant Phong ambient factor of the ray-cast colour")
      ->capture_default_str()
      ->check(non_negative());
  cmd->add_option("--seed", o->seed, "seed of the saccades")->capture_default_str();
  auto* gaze_option = cmd->add_option(
      "--gaze", o->gaze_source,
      "real eye movements instead of simulated saccades: a recording (EyeLink .asc, Pupil gaze_positions.csv, Tobii .tsv, t,x,y CSV; "
      "one step per fixation, every fixation unless --steps) or a live tracker pupil://HOST:PORT[?surface=NAME] (a step per new fixation)");
  o->gaze.fixation = "auto";  // steps go from fixation to fixation
  add_gaze_options(*cmd, o->gaze,
                   "--gaze: where the steps' fixations come from: auto (= nhr, the recommended event detector; pursuit a step every 100 "
                   "ms; live: I-VVT), nhp, "
                   "ivt (velocity threshold), idt (dispersion threshold) or tracker (the recording's own fixation events)");
  cmd->add_option("--display", o->gaze_display, "--gaze: the recording's screen W_CM,H_CM,DIST_CM (angles for the fixation filter)")
      ->capture_default_str()
      ->needs(gaze_option);
  cmd->add_option("--stimulus", o->stimulus,
                  "--gaze: where the render was shown on the recording's screen, X,Y,W,H in screen pixels (default: the whole screen)")
      ->needs(gaze_option);
  cmd->add_option("--start", o->start,
                  "--gaze recordings: skip the fixations that begin earlier than this many seconds after the first sample")
      ->capture_default_str()
      ->needs(gaze_option);
  cmd->add_option("--live-timeout", o->live_timeout, "--gaze live: stop when the tracker sends nothing for this many seconds")
      ->capture_default_str()
      ->needs(gaze_option);
  cmd->add_flag("--no-gaze-blinks", o->no_gaze_blinks,
                "--gaze: ignore the recording's blinks (by default a blink between fixations resets the field)")
      ->needs(gaze_option);
  cmd->add_option("--save-steps", o->save_steps,
                  "steps whose perceived image is saved (step_NNNN.png), e.g. 1,4,20,69; 'all' for every step")
      ->capture_default_str();
  cmd->add_option("-o,--output", o->output, "output folder (created)")->required()->check(an_output());
  cmd->add_option("--video", o->video, "also a video of every step's perceived image (ffmpeg)")->check(an_output());
  cmd->add_option("--stats", o->stats, "per-stage timings and per-step records as JSON")->check(an_output());
  cmd->add_flag("-q,--quiet", o->quiet, "print nothing on success");
  add_device_option(*cmd, o->device);

  return [o, steps_option] {
    o->steps_given = steps_option->count() > 0;
    return run_simulate(*o);
  };
}

}  // namespace foveal::app
