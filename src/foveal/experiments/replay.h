// foveal/experiments/replay.h — foveated-AO sequences that follow recorded or live gaze.
//
// Frame k starts at t_k = t_0 + k / fps. The gaze samples up to t_k go through the causal
// fixation filter (exactly as they would arrive from a tracker), and the filter's output at t_k,
// mapped from the recording's screen into render pixels, is the frame's gaze point. Until the
// first fixation the image centre is used. A recording is replayed on its own clock (as fast as
// frames render); a live source is paced on the wall clock.
#pragma once

#include "foveal/gaze/fixation.h"
#include "foveal/gaze/source.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/render/realtime.h"
#include "foveal/render/render.h"

#include <functional>
#include <optional>
#include <string>

namespace foveal {

struct ReplaySettings {
  double fps = 30;
  int frames = 0;         // 0: to the end of the recording (live: 10 s)
  double start_s = 0;     // recordings: seconds after the first sample
  double duration_s = 0;  // 0: everything from the start
  FixationMethod method = kRecommendedFixationMethod;
  FixationParams fixation;
  std::string stimulus;       // where the render sits on the screen, "X,Y,W,H" (empty: the whole screen)
  double live_timeout_s = 5;  // live: stop when the tracker stays silent this long
  bool reuse = true;          // a frame whose gaze equals the previous one's reuses its (identical) image
  // --realtime: each frame is what the real-time loop (render/realtime.h) shows at a display of
  // `fps` Hz: made within 1/fps of compute from the raw samples up to its time (the loop's own
  // saccade predictor, not the fixation filter, places the fovea)
  bool realtime = false;
  std::optional<double> budget_ms;  // realtime: what each frame may take, ms (unset: one frame, 1000/fps)
  bool predict = true;              // realtime: place the fovea at a saccade's predicted landing while it flies
  LandingParams landing;            // realtime: the landing predictor's parameters (gaze/landing.h)
  // realtime: what each frame keeps free for the machine's pauses, and the share of the budget the
  // periphery's rays may run to (LoopSettings' margin_ms and periphery_share; unset: the loop's)
  std::optional<double> margin_ms;
  double periphery_share = kDefaultPeripheryShare;
  bool rays_ahead = true;               // realtime: LoopSettings::rays_ahead
  double min_scale = kDefaultMinScale;  // realtime: LoopSettings::min_scale, the smallest size the loop may render at
  // The camera orbits its look point about its up axis at this speed, degrees per second of the
  // sequence (0: still): a moving view, on the renderer's temporal history (params.reuse.temporal)
  // or the real-time loop's kept rays
  double orbit_deg_s = 0;
  bool keep_history = true;  // realtime: a moving camera keeps the AO of the surfaces it still sees
};
// The sequence's camera at `t_s` seconds after its first frame (the orbit of orbit_deg_s).
Camera replay_camera(const Camera& camera, const ReplaySettings& settings, double t_s);
void validate(const ReplaySettings& settings);
// The real-time loop's settings for a replay (realtime): its budget, prediction, margin and share
LoopSettings replay_loop_settings(const ReplaySettings& settings);

struct ReplayFrame {
  int index = 0;
  double t_s = 0;                      // recording: since its first sample; live: since the start
  std::optional<glm::dvec2> gaze;      // latest raw sample at t_k, render pixels (unset: invalid)
  std::optional<glm::dvec2> fixation;  // filter output at t_k, render pixels (unset: none yet)
  glm::dvec2 render_gaze{0};           // the gaze the frame was rendered with
  uint64_t ao_rays = 0;                // AO rays of the image
  double ms = 0;                       // time to produce the frame (render or reuse)
  bool reused = false;
  SourceState state = SourceState::live;  // the source's state at t_k
  // realtime: the fraction of the fovea's pixels at full quality, and (a new view) the pixels
  // that kept AO rays from the view before
  double fovea_converged = NAN;
  uint64_t kept_pixels = 0;
  double scale = 1;        // realtime: the loop's render size / the size asked for (the frame is scaled up where < 1)
  bool late = false;       // realtime: the frame took longer than its budget
  bool predicted = false;  // realtime: render_gaze is a saccade's predicted landing, not the measured gaze
};

struct ReplaySummary {
  int frames = 0, reused = 0;
  uint64_t ao_rays = 0;
  double render_ms = 0;  // sum of the frames' ms
  double wall_ms = 0;
  std::string stopped;  // why it stopped early ("" when it ran to the end)
  // realtime: each frame's budget as the loop took it (unset without the loop), and the frames late
  std::optional<double> budget_ms, margin_ms;  // (margin_ms: what each frame kept free, as the loop took it)
  double periphery_share = kDefaultPeripheryShare;
  bool rays_ahead = true;
  double min_scale_allowed = kDefaultMinScale;  // (LoopSettings::min_scale)
  int late = 0;
  // realtime: the smallest render size the loop chose (a scale of the size asked for) and what it
  // said then (RealtimeLoop::note: why it lowered the size; "" where it never did), and what the
  // samples left its predictor (RealtimeLoop::gaze_note at the end; "" where nothing)
  double min_scale = 1;
  std::string scale_note, gaze_note;
  // realtime: what the loop said where it first held its size at min_scale, its frames late for
  // their base shading ("" where it never did)
  std::string held_note;
};

using ReplaySink = std::function<void(const ReplayFrame&, const Frame&)>;
using ReplayProgress = std::function<void(int done, int total)>;

// Frames at which a recording replay renders (t_0 and count) for the settings.
int replay_frame_count(const Recording& recording, const ReplaySettings& settings);

// Replay a recording: each frame rendered by `renderer` (any device; with params.reuse.temporal it
// builds on the renderer's history). The sink reads the frame's colour and stats only.
// `display` gives the angles for the filter (its physical size; the recording's screen pixels).
ReplaySummary replay_recording(const Recording& recording, const Display& display, FrameRenderer& renderer, const Camera& camera,
                               const RenderParams& params, const ReplaySettings& settings, const ReplaySink& sink,
                               const ReplayProgress& progress = {});

// The same with the real-time loop (settings.realtime): frame k is the loop's frame at t_k, made
// within 1/fps; ReplayFrame::render_gaze is where the loop placed the fovea. The sink's Frame holds
// the colour only.
ReplaySummary replay_recording_realtime(const Recording& recording, const Display& display, FrameRenderer& renderer, const Scene& scene,
                                        const Camera& camera, const RenderParams& params, const ReplaySettings& settings,
                                        const ReplaySink& sink, const ReplayProgress& progress = {});
ReplaySummary replay_live_realtime(GazeSource& source, const Display& display, FrameRenderer& renderer, const Scene& scene,
                                   const Camera& camera, const RenderParams& params, const ReplaySettings& settings, const ReplaySink& sink,
                                   const ReplayProgress& progress = {});

// The gaze replay_recording() renders each frame with (the fixation filter's output, the image
// centre before the first fixation), without rendering: the frames' records, render_gaze set.
std::vector<ReplayFrame> replay_gazes(const Recording& recording, const Display& display, const RenderParams& params,
                                      const ReplaySettings& settings);

// Follow a live source in real time. Stops after the frames (or 10 s), or — with `stopped` set —
// when the source has been silent or disconnected for live_timeout_s.
ReplaySummary replay_live(GazeSource& source, const Display& display, FrameRenderer& renderer, const Camera& camera,
                          const RenderParams& params, const ReplaySettings& settings, const ReplaySink& sink,
                          const ReplayProgress& progress = {});

}  // namespace foveal
