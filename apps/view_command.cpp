// apps/view_command.cpp — `foveal view`: the interactive viewer (GLFW + Dear ImGui).
#include "commands.h"
#include "foveal/ui/session.h"
#include "foveal/ui/window.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"

#include <fmt/core.h>

#include <filesystem>
#include <memory>
#include <regex>

namespace foveal::app {

namespace {

// The command's options as typed.
struct ViewCommandOptions {
  ViewOptions view;
  RenderOptions render;
  GazeOptions gaze;
  std::string mode = "foveated", source = "mouse", stimulus, overlays = "gaze", screenshot, window_screenshot, eye = "healthy";
  double speed = 1, starvation = 0.015, timeout = 600;
  std::optional<double> pupil;  // not given: the eye's (a profile's pupil_mm, else 3.5)
  float diff_gain = 8;
  int frames = 0, blink_every = 0;
  bool no_panel = false, no_progressive = false, realtime = false, no_predict = false;
  std::string landing;
  double frame_budget_ms = 10;
  LoopOptions loop;
  std::string device = "auto";
};

// Options → the session's settings, the gaze input and the window; runs until the window closes.
int run_view(const ViewCommandOptions& o) {
  const ThreadScope threads(o.view.threads);
  ViewSettings s;
  s.render = resolve_render_params(o.view, o.render);
  const ComputeDevice device = choose_device(o.device);
  s.cuda = device == ComputeDevice::cuda;
  s.mode = parse_view_mode(o.mode);
  s.eye = o.eye;
  s.eye_overrides.pupil_diameter_mm = o.pupil;
  s.vision.starvation = o.starvation;
  s.vision.blink_every = o.blink_every;
  s.diff_gain = o.diff_gain;
  s.progressive = !o.no_progressive;
  s.realtime = o.realtime;
  s.frame_budget_ms = o.frame_budget_ms;
  s.predict = !o.no_predict;
  s.landing = resolve_landing(o.landing, o.realtime && !o.no_predict);
  if (o.loop.given() && !o.realtime) fail("{} needs --realtime (only the real-time loop has a frame deadline)", o.loop.given_name());
  s.margin_ms = o.loop.margin_ms;
  s.periphery_share = o.loop.periphery_share.value_or(kDefaultPeripheryShare);
  s.rays_ahead = !o.loop.no_rays_ahead;
  s.min_scale = o.loop.min_scale.value_or(kDefaultMinScale);
  if (o.realtime && s.mode != ViewMode::foveated) fail("--realtime: the real-time loop shows the foveated mode (--mode foveated)");
  resolve(s);  // (every setting, whatever the mode: a value out of range is a mistake either way)
  WindowOptions w;
  w.overlays = parse_overlays(o.overlays);
  w.frames = o.frames;
  w.screenshot = o.screenshot;
  w.window_screenshot = o.window_screenshot;
  w.panel = !o.no_panel;
  w.converge_timeout_s = o.timeout;
  if (o.frames > 0 && o.screenshot.empty() && o.window_screenshot.empty())
    fail("--frames: give --screenshot or --window-screenshot too (what the run is for)");
  if (o.frames == 0 && !o.window_screenshot.empty()) fail("--window-screenshot: needs --frames");
  if (!(o.speed > 0)) fail("--speed: must be positive, got {}", o.speed);
  if (!(o.timeout > 0)) fail("--timeout: must be positive seconds, got {}", o.timeout);

  // The gaze: the mouse, a fixed point, a recording or a tracker
  GazeInput gaze;
  const glm::ivec2 render_px(s.render.width, s.render.height);
  gaze.display = s.render.display;
  if (o.gaze.fixation == "none")
    gaze.filter.reset();
  else
    gaze.filter = parse_fixation_method(o.gaze.fixation);
  gaze.fixation = resolve_fixation_params(o.gaze);
  std::string source_name = o.source;
  if (o.source == "mouse") {
    gaze.source = std::make_unique<MouseSource>(render_px);
    gaze.mapping = make_screen_mapping(render_px, render_px);
  } else if (o.source.find("://") != std::string::npos) {
    if (o.source.rfind("pupil://", 0) != 0)
      fail("--gaze: unknown live source '{}' (live trackers: pupil://HOST:PORT[?surface=NAME])", o.source);
    const ReadOptions read = resolve_read_options(o.gaze, s.render.display);
    gaze.source = std::make_unique<PupilSource>(o.source, read.screen_px, read.min_confidence);
    gaze.mapping = make_screen_mapping(gaze.source->screen_px(), render_px, o.stimulus);
  } else if (std::regex_match(o.source, std::regex(R"(\s*[-+0-9.eE]+\s*,\s*[-+0-9.eE]+\s*)")) && !std::filesystem::exists(o.source)) {
    gaze.fixed_px = parse_vec2("--gaze", o.source);
  } else {
    const ReadOptions read = resolve_read_options(o.gaze, s.render.display);
    Recording recording = read_recording_warned(o.source, read);
    if (recording.samples.empty()) fail("{}: no samples", recording.source);
    const glm::ivec2 screen = recording.screen_px;
    gaze.source = std::make_unique<RecordingPlayback>(std::move(recording), o.speed);
    gaze.mapping = make_screen_mapping(screen, render_px, o.stimulus);
  }

  const Scene scene = load_scene(o.view.scene);
  const Camera camera = resolve_camera(scene, o.view);
  const Tracer tracer(scene, parse_trace_api(o.render.trace_api));
  ViewSession session(scene, tracer, camera, s, std::move(gaze));
  w.title = fmt::format("foveal view — {} ({} triangles)", scene.source, tracer.triangles());
  run_window(session, w);
  if (!o.screenshot.empty() && o.frames > 0) {
    const ViewStatus st = session.status();
    fmt::print("foveal view: {} mode, {}x{}, gaze {}, {} → {} ({}, {:.0f} ms)\n", to_string(s.mode), s.render.width, s.render.height,
               source_name, st.stage, o.screenshot, st.converged ? "converged" : "not converged", st.render_ms);
    fmt::print("  device   {}\n", describe_device(device));
  }
  return 0;
}

}  // namespace

std::function<int()> add_view_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("view",
                                 "interactive viewer: foveated AO, the reference, both side by side, or the simulated eye, following the "
                                 "mouse, a recording or a live tracker");

  auto o = std::make_shared<ViewCommandOptions>();
  o->view.eye_option = "--from";
  o->render.mode_option = false;
  o->gaze.fixation = to_string(kRecommendedFixationMethod);
  add_view_options(*cmd, o->view);
  cmd->add_option(
         "--mode", o->mode,
         "foveated, reference (n_max rays everywhere), side-by-side (foveated | reference | difference) or vision (the simulated eye)")
      ->capture_default_str();
  cmd->add_option(
         "--gaze", o->source,
         "mouse (the cursor over the image), X,Y (a fixed point, render pixels), a recording (EyeLink .asc, Pupil gaze_positions.csv, "
         "Tobii .tsv, t,x,y CSV; played in real time) or a live tracker pupil://HOST:PORT[?surface=NAME]")
      ->capture_default_str();
  add_render_options(*cmd, o->render);
  add_gaze_options(
      *cmd, o->gaze,
      "how raw gaze becomes the fixation the render follows: ivvt (velocity threshold, smooth pursuit followed), ivt (velocity threshold), "
      "idt (dispersion threshold), mean, or none (every sample)");
  cmd->add_option("--stimulus", o->stimulus,
                  "recordings and trackers: where the render is on their screen, X,Y,W,H in screen pixels (default: the whole screen)");
  cmd->add_option("--speed", o->speed, "recordings: playback speed (1 = real time)")->capture_default_str();
  cmd->add_option(
         "--eye", o->eye,
         "vision mode: healthy, glaucoma[:SEVERITY 0..1], myopia:-D, hyperopia:D, presbyopia:AGE, astigmatism:CYL[@AXIS]; join with '+'")
      ->capture_default_str();
  cmd->add_option("--pupil", o->pupil,
                  "vision mode: pupil diameter, mm (overrides a profile's pupil_mm; default: the profile's, else 3.5)");
  cmd->add_option("--starvation", o->starvation, "vision mode: remembered CoCs grow by this fraction per step")->capture_default_str();
  cmd->add_option("--blink-every", o->blink_every, "vision mode: a blink (the field forgets) every N steps; 0 = never")
      ->capture_default_str();
  cmd->add_option("--overlays", o->overlays,
                  "drawn over the image: gaze, contours (q = 1, 0.5, 0.25), budget (AO heat map), scanpath, sharp (vision); "
                  "comma-separated, all or none")
      ->capture_default_str();
  cmd->add_option("--diff-gain", o->diff_gain, "side-by-side: the difference pane shows |foveated − reference| × this")
      ->capture_default_str();
  cmd->add_flag("--no-progressive", o->no_progressive, "no quarter-resolution preview before each full frame");
  cmd->add_flag("--realtime", o->realtime,
                "foveated mode: a frame every displayed frame from the real-time loop (the fovea refined first, at a saccade's "
                "predicted landing while it flies; docs/realtime.md) instead of whole frames for the filtered fixation");
  cmd->add_option("--frame-budget-ms", o->frame_budget_ms, "--realtime: what each frame may take of the window's refresh, ms")
      ->capture_default_str();
  cmd->add_flag("--no-predict", o->no_predict, "--realtime: keep the fovea at the measured gaze during saccades");
  add_landing_option(*cmd, o->landing, "--realtime: ");
  add_loop_options(*cmd, o->loop, "--realtime: ");
  cmd->add_option("--frames", o->frames,
                  "show this many frames, wait for the finished image, write --screenshot, and exit (scripts, tests)")
      ->check(CLI::Range(0, 1000000));
  cmd->add_option("--screenshot", o->screenshot,
                  "screenshot path (.png; its stats go beside it as .json); key P writes it (numbered when it exists)")
      ->check(output_file());
  cmd->add_option("--window-screenshot", o->window_screenshot, "with --frames: also a PNG of the whole window, panel included")
      ->check(output_file());
  cmd->add_option("--timeout", o->timeout, "--frames: longest wait for the finished image, seconds")->capture_default_str();
  cmd->add_flag("--no-panel", o->no_panel, "start with the parameter panel hidden (Tab toggles it)");

  add_device_option(*cmd, o->device);
  return [o] { return run_view(*o); };
}

}  // namespace foveal::app
