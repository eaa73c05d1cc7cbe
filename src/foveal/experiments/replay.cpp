// foveal/experiments/replay.cpp — gaze-following frame sequences.
#include "foveal/experiments/replay.h"

#include "foveal/render/outputs.h"
#include "foveal/util/error.h"
#include "foveal/util/timer.h"

#include <chrono>
#include <cmath>
#include <thread>

namespace foveal {

LoopSettings replay_loop_settings(const ReplaySettings& s) {
  LoopSettings l;
  l.budget_ms = s.budget_ms.value_or(1000.0 / s.fps);
  l.predict = s.predict;
  l.landing = s.landing;
  l.keep_history = s.keep_history;
  l.margin_ms = s.margin_ms;
  l.periphery_share = s.periphery_share;
  l.rays_ahead = s.rays_ahead;
  l.min_scale = s.min_scale;
  return l;
}

void validate(const ReplaySettings& s) {
  if (!(s.fps > 0 && s.fps <= 1000)) fail("fps: must be in (0, 1000], got {}", s.fps);
  if (s.frames < 0) fail("frames: must be zero (all) or positive, got {}", s.frames);
  if (!(s.start_s >= 0) || !std::isfinite(s.start_s)) fail("start_s: must be zero or positive seconds, got {}", s.start_s);
  if (!(s.duration_s >= 0) || !std::isfinite(s.duration_s))
    fail("duration_s: must be zero (all) or positive seconds, got {}", s.duration_s);
  if (!(s.live_timeout_s > 0)) fail("live_timeout_s: must be positive seconds, got {}", s.live_timeout_s);
  if (!std::isfinite(s.orbit_deg_s) || std::abs(s.orbit_deg_s) > 3600)
    fail("orbit_deg_s: must be within ±3600 degrees per second, got {}", s.orbit_deg_s);
  if (s.budget_ms && !s.realtime) fail("frame_budget_ms: is the real-time loop's (realtime)");
  if (s.budget_ms && !(*s.budget_ms > 0 && *s.budget_ms <= 1000 / s.fps))
    fail("frame_budget_ms: must be in (0, {:g}] ms (a frame at {:g} Hz), got {}", 1000 / s.fps, s.fps, *s.budget_ms);
  if (!s.realtime && (s.margin_ms || s.periphery_share != kDefaultPeripheryShare || !s.rays_ahead || s.min_scale != kDefaultMinScale))
    fail("{}: is the real-time loop's (realtime)", s.margin_ms                                   ? "margin_ms"
                                                   : s.periphery_share != kDefaultPeripheryShare ? "periphery_share"
                                                   : !s.rays_ahead                               ? "rays_ahead"
                                                                                                 : "min_scale");
  if (s.realtime) validate(replay_loop_settings(s));
  validate(s.fixation);
}

Camera replay_camera(const Camera& camera, const ReplaySettings& s, double t_s) {
  return s.orbit_deg_s == 0 ? camera : orbit_camera(camera, s.orbit_deg_s * t_s);
}

namespace {

// Renders frames, reusing the last one when the gaze has not moved.
class FrameMaker {
 public:
  FrameMaker(FrameRenderer& renderer, const RenderParams& params, bool reuse) : renderer_(renderer), params_(params), reuse_(reuse) {}

  // The frame for `gaze` seen from `view` (the sequence's camera at its time, replay_camera)
  const Frame& make(glm::dvec2 gaze, const Camera& view, ReplayFrame& info) {
    const Timer clock;
    info.render_gaze = gaze;
    // With temporal reuse every frame adds rays, so none is a copy of the last; nor is a moved view
    info.reused = reuse_ && !params_.reuse.temporal && last_gaze_ && *last_gaze_ == gaze && same_camera(view, last_camera_);
    if (!info.reused) {
      RenderParams p = params_;
      p.gaze_px = gaze;
      FrameOptions options;
      options.outputs = FrameOutputs::colour_only();  // the sink needs nothing else
      frame_ = renderer_.render(view, p, options);
      last_gaze_ = gaze;
      last_camera_ = view;
    }
    info.ao_rays = frame_.stats.ao_rays;
    info.ms = clock.ms();
    return frame_;
  }

 private:
  FrameRenderer& renderer_;
  const RenderParams& params_;
  bool reuse_;
  std::optional<glm::dvec2> last_gaze_;
  Camera last_camera_;
  Frame frame_;
};

// Makes frames with the real-time loop: the raw samples go in as they come, a frame per call.
class LoopMaker {
 public:
  LoopMaker(FrameRenderer& renderer, const Scene& scene, const Camera& camera, const RenderParams& params, const ReplaySettings& s)
      : loop_(renderer, scene, params, replay_loop_settings(s)), width_(params.width), height_(params.height) {
    loop_.frame(camera);  // the view's surfaces, before the first frame is due
  }
  void push(const GazeSample& g, std::optional<glm::dvec2> render_px) { loop_.push_gaze(g.t_s, g.valid ? render_px : std::nullopt); }
  // The loop's part of the summary: its budget, the smallest size it chose and why, and what the
  // samples left its predictor
  void finish(ReplaySummary& summary) const {
    summary.budget_ms = loop_.settings().budget_ms;
    summary.margin_ms = loop_margin_ms(loop_.settings());
    summary.periphery_share = loop_.settings().periphery_share;
    summary.rays_ahead = loop_.settings().rays_ahead;
    summary.min_scale_allowed = loop_.settings().min_scale;
    summary.min_scale = min_scale_;
    summary.scale_note = scale_note_;
    summary.held_note = held_note_;
    summary.gaze_note = loop_.gaze_note();
  }
  // The loop's next frame, seen from `view` (the sequence's camera at its time, replay_camera)
  const Frame& make(const Camera& view, ReplayFrame& info) {
    loop_.recycle(std::move(frame_.color));  // the last frame is written: composed into again
    LoopFrame f = loop_.frame(view);
    info.render_gaze = f.gaze_px / f.scale;  // (the frame's own size: the loop's scale() may be the next frame's)
    info.ao_rays = f.rays;
    info.ms = f.ms;
    info.fovea_converged = f.fovea_converged;
    info.kept_pixels = f.kept_pixels;
    info.late = f.late;
    info.predicted = f.predicted;
    // Every frame at the size asked for (a video needs one size; the gaze columns are in its
    // pixels): where the loop rendered smaller, scaled up as a display would show it
    info.scale = f.scale;
    if (info.scale < min_scale_) {
      min_scale_ = info.scale;
      scale_note_ = loop_.note();
    }
    if (loop_.size_held() && held_note_.empty()) held_note_ = loop_.note();
    if (f.color.width != width_ || f.color.height != height_) f.color = scaled_nearest(f.color, width_, height_);
    frame_.color = std::move(f.color);
    frame_.gaze_px = info.render_gaze;
    frame_.stats.ao_rays = f.rays;
    frame_.stats.total_ms = f.ms;
    return frame_;
  }

 private:
  RealtimeLoop loop_;
  int width_, height_;  // the size asked for
  Frame frame_;
  double min_scale_ = 1;
  std::string scale_note_, held_note_;
};

// Walks a recording's frames: for each, the samples up to t_k through the causal fixation filter
// (and to `sample(g, render_px)`), then `frame(info)` with the frame's record (gaze, fixation,
// state) filled in.
template <typename OnFrame, typename OnSample>
void walk_recording(const Recording& r, const Display& display, const RenderParams& params, const ReplaySettings& s, OnFrame&& frame,
                    OnSample&& sample) {
  validate(s);
  if (r.samples.empty()) fail("{}: no samples to replay", r.source);
  const GazeGeometry geometry(display, r.screen_px);
  const ScreenMapping mapping = make_screen_mapping(r.screen_px, {params.width, params.height}, s.stimulus);
  FixationTracker tracker(s.method, s.fixation, geometry);
  const int count = replay_frame_count(r, s);
  const double first = r.samples.front().t_s, t0 = first + s.start_s;
  const glm::dvec2 centre(0.5 * params.width, 0.5 * params.height);
  size_t next = 0;
  for (int k = 0; k < count; ++k) {
    const double t = t0 + k / s.fps;
    const GazeSample* latest = nullptr;
    while (next < r.samples.size() && r.samples[next].t_s <= t) {
      tracker.push(r.samples[next]);
      sample(r.samples[next], mapping.to_render(r.samples[next].px));
      latest = &r.samples[next++];
    }
    ReplayFrame info;
    info.index = k;
    info.t_s = t - first;
    info.state = next >= r.samples.size() ? SourceState::ended : next == 0 ? SourceState::waiting : SourceState::live;
    if (latest && latest->valid) info.gaze = mapping.to_render(latest->px);
    if (const auto f = tracker.frame_gaze()) info.fixation = mapping.to_render(*f);
    info.render_gaze = info.fixation.value_or(centre);
    frame(info, k, count);
  }
}

template <typename OnFrame>
void walk_recording(const Recording& r, const Display& display, const RenderParams& params, const ReplaySettings& s, OnFrame&& frame) {
  walk_recording(r, display, params, s, frame, [](const GazeSample&, glm::dvec2) {});
}

void account(ReplaySummary& summary, const ReplayFrame& f) {
  ++summary.frames;
  summary.reused += f.reused;
  if (!f.reused) summary.ao_rays += f.ao_rays;
  summary.render_ms += f.ms;
  summary.late += f.late;
}

}  // namespace

int replay_frame_count(const Recording& r, const ReplaySettings& s) {
  if (s.frames > 0) return s.frames;
  double span = r.duration_s() - s.start_s;
  if (s.duration_s > 0) span = std::min(span, s.duration_s);
  if (span < 0) fail("start_s: {} s is past the end of the recording ({:.3f} s long)", s.start_s, r.duration_s());
  return static_cast<int>(std::floor(span * s.fps + 1e-9)) + 1;
}

ReplaySummary replay_recording(const Recording& r, const Display& display, FrameRenderer& renderer, const Camera& camera,
                               const RenderParams& params, const ReplaySettings& s, const ReplaySink& sink,
                               const ReplayProgress& progress) {
  const Timer wall;
  FrameMaker maker(renderer, params, s.reuse);
  ReplaySummary summary;
  walk_recording(r, display, params, s, [&](ReplayFrame& info, int k, int count) {
    const Frame& frame = maker.make(info.render_gaze, replay_camera(camera, s, k / s.fps), info);
    account(summary, info);
    sink(info, frame);
    if (progress) progress(k + 1, count);
  });
  summary.wall_ms = wall.ms();
  return summary;
}

ReplaySummary replay_recording_realtime(const Recording& r, const Display& display, FrameRenderer& renderer, const Scene& scene,
                                        const Camera& camera, const RenderParams& params, const ReplaySettings& s, const ReplaySink& sink,
                                        const ReplayProgress& progress) {
  validate(s);
  const Timer wall;
  LoopMaker maker(renderer, scene, camera, params, s);
  ReplaySummary summary;
  walk_recording(
      r, display, params, s,
      [&](ReplayFrame& info, int k, int count) {
        const Frame& frame = maker.make(replay_camera(camera, s, k / s.fps), info);
        account(summary, info);
        sink(info, frame);
        if (progress) progress(k + 1, count);
      },
      [&](const GazeSample& g, glm::dvec2 px) { maker.push(g, px); });
  summary.wall_ms = wall.ms();
  maker.finish(summary);
  return summary;
}

std::vector<ReplayFrame> replay_gazes(const Recording& r, const Display& display, const RenderParams& params, const ReplaySettings& s) {
  std::vector<ReplayFrame> frames;
  walk_recording(r, display, params, s, [&](ReplayFrame& info, int, int) { frames.push_back(info); });
  return frames;
}

namespace {

// Follows a live source in real time: frame k due k/fps after the start (late frames are not
// skipped, just late); `samples(polled)` takes each poll's samples, `make(info)` the frame.
template <typename OnSamples, typename MakeFrame>
ReplaySummary follow_live(GazeSource& source, const ScreenMapping& mapping, const ReplaySettings& s, const ReplaySink& sink,
                          const ReplayProgress& progress, OnSamples&& on_samples, MakeFrame&& make) {
  const Timer wall;
  const int count = s.frames > 0 ? s.frames : static_cast<int>(std::ceil((s.duration_s > 0 ? s.duration_s : 10.0) * s.fps));
  ReplaySummary summary;
  std::vector<GazeSample> samples;
  for (int k = 0; k < count; ++k) {
    const double due_ms = 1000.0 * k / s.fps, now_ms = wall.ms();
    if (due_ms > now_ms) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(due_ms - now_ms));
    samples.clear();
    source.poll(samples);
    on_samples(samples);
    ReplayFrame info;
    info.index = k;
    info.t_s = wall.ms() / 1000.0;
    info.state = source.state();
    if (!samples.empty() && samples.back().valid) info.gaze = mapping.to_render(samples.back().px);
    const Frame& frame = make(info);
    account(summary, info);
    sink(info, frame);
    if (progress) progress(k + 1, count);
    const bool gone = info.state == SourceState::disconnected || info.state == SourceState::ended;
    if ((gone || info.state == SourceState::stale || info.state == SourceState::waiting) && source.silent_s() > s.live_timeout_s) {
      summary.stopped = fmt::format("{}: no gaze for {:.1f} s ({}); stopped after {} frames", source.name(), source.silent_s(),
                                    gone ? to_string(info.state) : "tracker silent", summary.frames);
      break;
    }
  }
  summary.wall_ms = wall.ms();
  return summary;
}

}  // namespace

ReplaySummary replay_live(GazeSource& source, const Display& display, FrameRenderer& renderer, const Camera& camera,
                          const RenderParams& params, const ReplaySettings& s, const ReplaySink& sink, const ReplayProgress& progress) {
  validate(s);
  const glm::ivec2 screen = source.screen_px();
  const GazeGeometry geometry(display, screen);
  const ScreenMapping mapping = make_screen_mapping(screen, {params.width, params.height}, s.stimulus);
  FixationTracker tracker(s.method, s.fixation, geometry);
  FrameMaker maker(renderer, params, s.reuse);
  const glm::dvec2 centre(0.5 * params.width, 0.5 * params.height);
  return follow_live(
      source, mapping, s, sink, progress,
      [&](const std::vector<GazeSample>& samples) {
        for (const GazeSample& g : samples) tracker.push(g);
      },
      [&](ReplayFrame& info) -> const Frame& {
        if (const auto f = tracker.frame_gaze()) info.fixation = mapping.to_render(*f);
        return maker.make(info.fixation.value_or(centre), replay_camera(camera, s, info.t_s), info);
      });
}

ReplaySummary replay_live_realtime(GazeSource& source, const Display& display, FrameRenderer& renderer, const Scene& scene,
                                   const Camera& camera, const RenderParams& params, const ReplaySettings& s, const ReplaySink& sink,
                                   const ReplayProgress& progress) {
  validate(s);
  (void)display;  // the loop's saccade predictor measures angles on the render's display
  const ScreenMapping mapping = make_screen_mapping(source.screen_px(), {params.width, params.height}, s.stimulus);
  LoopMaker maker(renderer, scene, camera, params, s);
  ReplaySummary summary = follow_live(
      source, mapping, s, sink, progress,
      [&](const std::vector<GazeSample>& samples) {
        for (const GazeSample& g : samples) maker.push(g, mapping.to_render(g.px));
      },
      [&](ReplayFrame& info) -> const Frame& { return maker.make(replay_camera(camera, s, info.t_s), info); });
  maker.finish(summary);
  return summary;
}

}  // namespace foveal
