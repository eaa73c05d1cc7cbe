// apps/replay_command.cpp — `foveal replay`: a foveated-AO sequence that follows a recording or
// a live tracker; frames (PNG), frames.csv, optionally a video and stats JSON.
#include "commands.h"
#include "foveal/io/image_io.h"
#include "foveal/render/outputs.h"
#include "foveal/io/video.h"
#include "foveal/experiments/replay.h"
#include "foveal/util/files.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/util/timer.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <unistd.h>

namespace foveal::app {

namespace {

std::string cell(const std::optional<glm::dvec2>& p, int axis) { return p ? fmt::format("{:.2f}", (*p)[axis]) : std::string(); }

// The command's options as typed.
struct ReplayOptions {
  ViewOptions view;
  RenderOptions render;
  GazeOptions gaze;
  std::string source, output, video, stats, stimulus, landing;
  std::optional<double> fps, refresh_hz, budget_ms;  // (fps: 30, or with --realtime 60)
  double start = 0, duration = 0, live_timeout = 5, orbit = 0;
  int frames = 0;
  bool no_reuse = false, mark = false, quiet = false, realtime = false, no_predict = false, no_history = false;
  LoopOptions loop;
  std::string device = "auto";
};

// The sequence's settings from the options (checked).
ReplaySettings replay_settings(const ReplayOptions& o) {
  ReplaySettings settings;
  // --realtime: frames at the display's refresh (--refresh-hz, the loop's name for it, or --fps; 60 Hz)
  if (o.refresh_hz && !o.realtime) fail("--refresh-hz needs --realtime (a replay's frames per second of gaze time are --fps)");
  if (o.budget_ms && !o.realtime) fail("--frame-budget-ms needs --realtime (only the real-time loop has a frame budget)");
  if (o.refresh_hz && o.fps && *o.refresh_hz != *o.fps)
    fail("--refresh-hz {:g} and --fps {:g}: with --realtime both are the display's refresh; give one", *o.refresh_hz, *o.fps);
  settings.fps = o.refresh_hz.value_or(o.fps.value_or(o.realtime ? 60.0 : 30.0));
  settings.budget_ms = o.budget_ms;
  settings.frames = o.frames;
  settings.start_s = o.start;
  settings.duration_s = o.duration;
  settings.method = parse_fixation_method(o.gaze.fixation);
  settings.fixation = resolve_fixation_params(o.gaze);
  settings.stimulus = o.stimulus;
  settings.live_timeout_s = o.live_timeout;
  settings.reuse = !o.no_reuse;
  settings.realtime = o.realtime;
  settings.predict = !o.no_predict;
  settings.landing = resolve_landing(o.landing, o.realtime && !o.no_predict);
  settings.orbit_deg_s = o.orbit;
  settings.keep_history = !o.no_history;
  if (o.loop.given() && !o.realtime) fail("{} needs --realtime (only the real-time loop has a frame deadline)", o.loop.given_name());
  settings.margin_ms = o.loop.margin_ms;
  settings.periphery_share = o.loop.periphery_share.value_or(kDefaultPeripheryShare);
  settings.rays_ahead = !o.loop.no_rays_ahead;
  settings.min_scale = o.loop.min_scale.value_or(kDefaultMinScale);
  for (const auto& [option, path] : {std::pair{"--stats", &o.stats}, std::pair{"--video", &o.video}})
    check_output_beside_folder(option, *path, o.output, [](const std::string& name) {
      return name == "frames.csv" || (name.rfind("frame_", 0) == 0 && lower_extension(name) == ".png");
    });
  if (o.no_predict && !o.realtime) fail("--no-predict needs --realtime");
  if (o.no_history && !o.realtime) fail("--no-history needs --realtime (without it, --temporal keeps rays across frames)");
  validate(settings);
  return settings;
}

// The frames' writer: frame_NNNNN.png (the gaze marked with --mark) and a line of frames.csv each.
class FrameWriter {
 public:
  // The frames go into a staging folder beside the output, moved into place by commit(): a run that
  // fails (on its first frame, say) leaves no half-written folder behind
  FrameWriter(const ReplayOptions& o) : o_(o), staged_(o.output), dir_(staged_.path()) {
    csv_path_ = (dir_ / "frames.csv").string();
    csv_.open(csv_path_);
    if (!csv_) fail("{}: cannot write", csv_path_);
    csv_ << "frame,t_s,gaze_x,gaze_y,fix_x,fix_y,ao_rays,ms,reused,source_state,fovea_converged,kept_pixels,scale,fovea_x,fovea_y,"
            "predicted,late\n";
  }
  void operator()(const ReplayFrame& f, const Frame& frame) {
    const std::string path = (dir_ / fmt::format("frame_{:05d}.png", f.index)).string();
    if (o_.mark) {
      Image marked = frame.color;
      mark_gaze(marked, f.render_gaze);
      save_image(marked, path);
    } else {
      save_image(frame.color, path);
    }
    const auto realtime = [&](auto value) { return o_.realtime ? fmt::format("{}", value) : std::string(); };
    csv_ << fmt::format("{},{:.6f},{},{},{},{},{},{:.3f},{},{},{},{},{},{:.2f},{:.2f},{},{}\n", f.index, f.t_s, cell(f.gaze, 0),
                        cell(f.gaze, 1), cell(f.fixation, 0), cell(f.fixation, 1), f.ao_rays, f.ms, f.reused ? 1 : 0, to_string(f.state),
                        realtime(fmt::format("{:.4f}", f.fovea_converged)), realtime(f.kept_pixels),
                        realtime(fmt::format("{:.4f}", f.scale)), f.render_gaze.x, f.render_gaze.y, realtime(f.predicted ? 1 : 0),
                        realtime(f.late ? 1 : 0));
    csv_.flush();
  }
  void close() { csv_.close(); }
  void commit() { staged_.commit(); }
  std::string csv_path() const { return (std::filesystem::path(o_.output) / "frames.csv").string(); }
  std::string pattern() const { return (std::filesystem::path(o_.output) / "frame_%05d.png").string(); }  // after commit()

 private:
  const ReplayOptions& o_;
  StagedFolder staged_;
  std::filesystem::path dir_;
  std::string csv_path_;
  std::ofstream csv_;
};

// A progress bar on a terminal for sequences that take a while.
struct ProgressBar {
  bool show = false, shown = false;
  Timer clock;
  void operator()(int done, int total) {
    if (!show || clock.ms() < 1000) return;
    shown = true;
    const double rate = done / (clock.ms() / 1000);
    const int width = 30, filled = total > 0 ? width * done / total : 0;
    fmt::print(stderr, "\r  [{:<{}}] {}/{} frames  {:.1f} frames/s  ETA {:.0f} s ", std::string(filled, '#'), width, done, total, rate,
               rate > 0 ? (total - done) / rate : 0.0);
  }
  ~ProgressBar() {
    if (shown) fmt::print(stderr, "\r{:80}\r", "");
  }
};

// --stats: the sequence's totals.
nlohmann::json replay_stats_json(const ReplayOptions& o, const ReplaySettings& settings, const ReplaySummary& summary,
                                 const RenderParams& params, const FrameRenderer& renderer, const Scene& scene,
                                 const std::optional<Recording>& recording, bool live, int threads, ComputeDevice device) {
  const std::string& source_name = o.source;
  nlohmann::json j = {
      {"gaze_source", source_name},
      {"live", live},
      {"fixation", o.gaze.fixation},
      {"fps", settings.fps},
      {"frames", summary.frames},
      {"reused_frames", summary.reused},
      {"width", params.width},
      {"height", params.height},
      {"mode", to_string(params.mode)},
      {"seed", params.seed},
      {"threads", threads},
      {"device", to_string(device)},
      {"scene", {{"source", scene.source}, {"triangles", renderer.triangles()}, {"build_ms", renderer.build_ms()}}},
      {"rays", {{"ao", summary.ao_rays}}},
      {"time_ms",
       {{"frames", summary.render_ms},
        {"total", summary.wall_ms},
        {"per_rendered_frame", summary.frames > summary.reused ? summary.render_ms / (summary.frames - summary.reused) : 0.0}}},
      {"stopped", summary.stopped},
      {"budget_ms", summary.budget_ms ? nlohmann::json(*summary.budget_ms) : nlohmann::json(nullptr)},  // --realtime: the loop's
      {"margin_ms", summary.margin_ms ? nlohmann::json(*summary.margin_ms) : nlohmann::json(nullptr)},
      {"periphery_share", summary.budget_ms ? nlohmann::json(summary.periphery_share) : nlohmann::json(nullptr)},
      {"rays_ahead", summary.budget_ms ? nlohmann::json(summary.rays_ahead) : nlohmann::json(nullptr)},
      {"min_scale", summary.budget_ms ? nlohmann::json(summary.min_scale_allowed) : nlohmann::json(nullptr)},
      {"resolution_held_note", summary.budget_ms ? nlohmann::json(summary.held_note) : nlohmann::json(nullptr)},
      {"frames_late", summary.budget_ms ? nlohmann::json(summary.late) : nlohmann::json(nullptr)},
      {"resolution_scale_min", summary.budget_ms ? nlohmann::json(summary.min_scale) : nlohmann::json(nullptr)},
      {"resolution_note", summary.budget_ms ? nlohmann::json(summary.scale_note) : nlohmann::json(nullptr)},
      {"gaze_note", summary.budget_ms ? nlohmann::json(summary.gaze_note) : nlohmann::json(nullptr)},
      {"peak_rss_mib", peak_rss_mib()}};
  if (recording)
    j["recording"] = {{"format", to_string(recording->format)},
                      {"screen_px", {recording->screen_px.x, recording->screen_px.y}},
                      {"samples", recording->samples.size()}};
  return j;
}

void print_replay(const ReplayOptions& o, const ReplaySettings& settings, const ReplaySummary& summary, const RenderParams& params,
                  const FrameRenderer& renderer, const std::string& csv_path, int threads, const Recording* recording) {
  const std::string& source_name = o.source;
  if (settings.realtime)  // every frame is the loop's, its fovea from the raw samples (the filter steers nothing)
    fmt::print(
        "foveal replay: {} → {} frames at {:g} fps, {}x{}, the loop's fovea from the raw samples (landing prediction {}), {} threads\n",
        source_name, summary.frames, settings.fps, params.width, params.height, settings.predict ? "on" : "off", threads);
  else
    fmt::print("foveal replay: {} → {} frames at {:g} fps ({} rendered, {} reused: gaze unchanged), {}x{}, {} filter, {} threads\n",
               source_name, summary.frames, settings.fps, summary.frames - summary.reused, summary.reused, params.width, params.height,
               o.gaze.fixation, threads);
  fmt::print("  device   {}\n", renderer.describe());
  // A --duration past the recording's last sample: the frames end there (fewer than asked for)
  if (recording && settings.frames <= 0 && settings.duration_s > 0 && settings.start_s + settings.duration_s > recording->duration_s())
    fmt::print("  span     {:g}–{:.1f} s: the recording ends there ({:g} s asked for from {:g} s)\n", settings.start_s,
               recording->duration_s(), settings.duration_s, settings.start_s);
  if (summary.budget_ms)
    fmt::print("  loop     a frame every {:.1f} ms at {:g} Hz, each within {:.1f} ms: {} late of {}\n", 1000 / settings.fps, settings.fps,
               *summary.budget_ms, summary.late, summary.frames);
  if (summary.budget_ms && summary.min_scale < 1)  // frames.csv's scale says which frames
    fmt::print("  size     lowered to {:.0f} % at the least: {}\n", 100 * summary.min_scale, summary.scale_note);
  if (summary.budget_ms && !summary.held_note.empty()) fmt::print("  size     held: {}\n", summary.held_note);
  if (summary.budget_ms && !summary.gaze_note.empty()) fmt::print("  gaze     {}\n", summary.gaze_note);
  fmt::print("  time     {:.1f} s ({:.0f} ms per rendered frame), {:.1f} M AO rays\n", summary.wall_ms / 1000,
             summary.frames > summary.reused ? summary.render_ms / (summary.frames - summary.reused) : 0.0, summary.ao_rays / 1e6);
  fmt::print("  wrote    {}/frame_00000.png … , {}", o.output, csv_path);
  if (!o.video.empty()) fmt::print(", {}", o.video);
  if (!o.stats.empty()) fmt::print(", {}", o.stats);
  fmt::print("\n");
}

int run_replay(const ReplayOptions& o) {
  const ThreadScope threads(o.view.threads);
  const RenderParams params = resolve_render_params(o.view, o.render);
  // The gaze screen's physical size: --display without its resolution (which is for the render)
  const Display gaze_display = params.display;
  const ReplaySettings settings = replay_settings(o);
  const ReadOptions read = resolve_read_options(o.gaze, gaze_display);
  const bool live = o.source.rfind("pupil://", 0) == 0;
  if (!live && o.source.find("://") != std::string::npos)
    fail("--gaze: unknown live source '{}' (live trackers: pupil://HOST:PORT[?surface=NAME])", o.source);
  std::optional<Recording> recording;
  if (!live) recording = read_recording_warned(o.source, read);

  const Scene scene = load_scene(o.view.scene);
  const Camera camera = resolve_camera(scene, o.view);
  const ComputeDevice device = choose_device(o.device);
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(scene, device, parse_trace_api(o.render.trace_api));
  FrameWriter writer(o);
  ReplaySummary summary;
  {
    ProgressBar progress;
    progress.show = !o.quiet && isatty(fileno(stderr));
    const ReplaySink sink = [&](const ReplayFrame& f, const Frame& frame) { writer(f, frame); };
    const ReplayProgress bar = [&](int done, int total) { progress(done, total); };
    if (live) {
      PupilSource source(o.source, read.screen_px, read.min_confidence);
      summary = settings.realtime ? replay_live_realtime(source, gaze_display, *renderer, scene, camera, params, settings, sink, bar)
                                  : replay_live(source, gaze_display, *renderer, camera, params, settings, sink, bar);
    } else {
      summary = settings.realtime
                    ? replay_recording_realtime(*recording, gaze_display, *renderer, scene, camera, params, settings, sink, bar)
                    : replay_recording(*recording, gaze_display, *renderer, camera, params, settings, sink, bar);
    }
  }
  writer.close();
  writer.commit();  // whole: every frame rendered (a live session that stopped: up to the stop, as frames.csv says)
  if (!o.video.empty() && summary.frames > 0) encode_video(writer.pattern(), settings.fps, o.video);
  if (!o.stats.empty())
    write_json_file(o.stats, replay_stats_json(o, settings, summary, params, *renderer, scene, recording, live, threads.threads(), device));
  if (!summary.stopped.empty()) fail("{}", summary.stopped);
  if (!o.quiet)
    print_replay(o, settings, summary, params, *renderer, writer.csv_path(), threads.threads(), recording ? &*recording : nullptr);
  return 0;
}

}  // namespace

std::function<int()> add_replay_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("replay", "render a foveated-AO sequence that follows a gaze recording or a live tracker");

  auto o = std::make_shared<ReplayOptions>();
  cmd->add_option(
         "--gaze", o->source,
         "a recording (EyeLink .asc, Pupil gaze_positions.csv, Tobii .tsv, t,x,y CSV) or a live tracker: pupil://HOST:PORT[?surface=NAME]")
      ->required();
  add_view_options(*cmd, o->view);
  add_render_options(*cmd, o->render);
  add_gaze_options(*cmd, o->gaze);
  add_device_option(*cmd, o->device);
  cmd->add_option("-o,--output", o->output, "folder for frame_NNNNN.png and frames.csv (created)")->required()->check(an_output());
  cmd->add_option("--fps", o->fps, "frames per second of gaze time (default 30; with --realtime the display's refresh, 60)");
  cmd->add_option("--frames", o->frames, "number of frames (0: to the end of the recording; live: 10 s)")->capture_default_str();
  cmd->add_option("--start", o->start, "recordings: start this many seconds after the first sample")->capture_default_str();
  cmd->add_option("--duration", o->duration, "seconds of gaze to render (0: all)")->capture_default_str();
  cmd->add_option("--stimulus", o->stimulus,
                  "where the render was shown on the recording's screen, X,Y,W,H in screen pixels (default: the whole screen)");
  cmd->add_option("--live-timeout", o->live_timeout, "live: stop when the tracker sends nothing for this many seconds")
      ->capture_default_str();
  cmd->add_flag("--mark", o->mark, "draw a red cross at each frame's gaze point on the saved frames");
  cmd->add_flag("--realtime", o->realtime,
                "each frame is what the real-time loop shows on a display of --refresh-hz (or --fps) Hz: made within its budget "
                "of compute from the raw samples up to its time, the fovea refined first (docs/realtime.md); frames.csv's ms is "
                "each frame's time");
  cmd->add_option("--refresh-hz", o->refresh_hz, "--realtime: the display's refresh rate, Hz: a frame each (60; --fps says the same)")
      ->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--frame-budget-ms", o->budget_ms,
                  "--realtime: what each frame may take of the refresh, ms (default: all of it; less leaves the rest to an "
                  "application's own drawing)");
  cmd->add_flag("--no-predict", o->no_predict, "--realtime: keep the fovea at the measured gaze during saccades (no landing prediction)");
  add_landing_option(*cmd, o->landing, "--realtime: ");
  add_loop_options(*cmd, o->loop, "--realtime: ");
  cmd->add_option("--orbit", o->orbit,
                  "the camera orbits its look point about its up axis at this many degrees per second of the sequence (a moving "
                  "view; with --realtime the loop keeps the AO of the surfaces it still sees, without it use --temporal for that)")
      ->capture_default_str();
  cmd->add_flag("--no-history", o->no_history,
                "--realtime: a moved camera starts its AO afresh instead of keeping the rays of the surfaces it still sees");
  cmd->add_flag("--no-reuse", o->no_reuse, "render every frame, even when the gaze has not moved since the previous one");
  cmd->add_option("--video", o->video, "also encode the frames into a video with ffmpeg (.mp4, .mkv, .webm, …)")->check(an_output());
  cmd->add_option("--stats", o->stats, "write a summary of the sequence as JSON")->check(an_output());
  cmd->add_flag("-q,--quiet", o->quiet, "print nothing on success");

  return [o] { return run_replay(*o); };
}

}  // namespace foveal::app
