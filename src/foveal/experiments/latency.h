// foveal/experiments/latency.h — `bench latency`: gaze-to-photon latency of three display loops on
// recorded gaze, under a simulated clock.
//
// A recording is replayed as a tracker would deliver it: sample s reaches the renderer at
// t_s + latency (default: the sample period + 2 ms). The display refreshes every 1/refresh_hz; a
// frame started at a refresh is shown at the first refresh after it is done, and the next frame
// starts then. The clock advances by each frame's cost: with the wall clock its measured time,
// with the model clock a fixed cost model calibrated at the start of the run (reproducible). Three
// loops run on the same samples:
//   whole-frame          today's: render a whole foveated frame for the latest gaze, then show it;
//   deadline             RealtimeLoop (render/realtime.h) without prediction;
//   deadline+prediction  RealtimeLoop placing the fovea at each saccade's predicted landing;
//   deadline+oracle      (on request) the same with each saccade's true landing from its detected
//                        onset on: a perfect predictor, the most prediction could gain.
// For every saccade (detected in the recording, nhr) landing in the segment: the time from its
// landing to the first frame on screen from then on (the one shown when the eye lands included:
// 0 ms if it was ready) whose fovea — the q = 1 region around the true landing — is
// within the full-frame reference's own noise (RMSE against a reference of n_max rays per pixel,
// as a multiple of a second reference's RMSE against it: ratio ≤ 1 + 2 standard errors, as
// `bench quality` judges), and the ray-bound limit: that fovea's pixels × n_max over the raw
// tracing rate measured in the same run.
#pragma once

#include "foveal/gaze/recording.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/render/realtime.h"
#include "foveal/util/cpu_share.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace foveal {

struct LatencyParams {
  RenderParams render;                       // size, display, n_max, seed (the loops'); mode foveated
  double refresh_hz = 60;                    // the display's rate
  std::optional<double> budget_ms;           // unset: one refresh
  std::optional<double> tracker_latency_ms;  // unset: the recording's sample period + 2 ms
  LoopClock clock = LoopClock::wall;
  // The model clock's cost model: unset, measured on the view at the start; set, the run is the
  // same on any machine
  std::optional<double> model_rays_per_ms, model_fixed_ms;
  double start_s = 0, duration_s = 3;  // the segment replayed (seconds from the recording's first sample)
  double min_amplitude_deg = 2;        // smaller saccades are not judged
  std::vector<std::string> loops = {"whole-frame", "deadline", "deadline+prediction"};
  std::optional<double> margin_ms;                  // the deadline loops' least margin (unset: the loop's default, loop_margin_ms)
  double periphery_share = kDefaultPeripheryShare;  // the deadline loops' periphery: its rays up to this share of the budget
  bool rays_ahead = true;                           // the deadline loops' rays ahead of the gaze (LoopSettings::rays_ahead)
  double min_scale = kDefaultMinScale;              // the deadline loops' smallest size (LoopSettings::min_scale)
  LandingParams landing;  // the prediction loops' landing predictor (gaze/landing.h; the oracle's detects flights with it)
  // The first recording's judged saccade a timeline picture will draw (the last where there are
  // fewer): each frame also judges its fovea (LatencyFrame::drawn_error). Unset: no picture
  std::optional<size_t> timeline_saccade;
  // (tests) Called before each frame of a deadline loop with the frame's index in its segment: a
  // budget changed mid-segment, as an application's own work changes what it leaves the loop
  std::function<void(RealtimeLoop&, int)> before_frame;
};
// Check the parameters; throws Error naming the option.
void validate(const LatencyParams& params);

struct LatencySaccade {
  double amplitude_deg = 0;
  double duration_ms = 0;
  double landing_s = 0;                       // seconds from the recording's first sample
  glm::dvec2 landing_px{0};                   // render pixels
  std::optional<double> converged_ms;         // landing → a frame on screen with the fovea within noise (unset: not in the segment)
  double ray_bound_ms = 0;                    // the fovea's pixels × n_max / the raw rate
  double model_ray_bound_ms = NAN;            // model clock: … / the model's rate (the rays it allows)
  double fixation_ms = 0;                     // landing → the eye's next saccade or blink (any size), or the recording's end
  std::optional<double> predicted_error_deg;  // deadline+prediction: the last prediction shown before the landing, from it
  // Frames on screen after the landing, before its fovea converged, that were not judged
  // (LatencyLoop::frames_not_judged), so that converged_ms may be later than the eye saw it
  int frames_not_judged = 0;
};

struct LatencyFrame {  // one shown frame, for the timeline picture
  double start_s = 0, shown_s = 0;
  double cost_ms = 0;     // what the frame cost on the clock
  glm::dvec2 gaze_px{0};  // where the fovea was placed
  bool predicted = false;
  // The loop's own account (deadline loops): the AO rays it traced, its size (a share of the
  // references' width; a frame below 1 is judged as LatencyLoop::frames_lowered says), its fovea's
  // converged share, and on the wall
  // clock the time its foveation maps (with the estimate of the pixels without rays), its planning
  // (choosing the fovea's rays, and its sweeps over every pixel for the periphery's or those ahead),
  // its rays and composing its image (with the fovea's state) took
  uint64_t rays = 0;
  double scale = 1, fovea_converged = NAN;
  double maps_ms = NAN, plan_ms = NAN, trace_ms = NAN, compose_ms = NAN;
  uint32_t sweeps = 0;
  double fovea_error = NAN;  // RMSE in the fovea of the saccade being followed, over the reference noise (NaN: none)
  // The same for the timeline picture's saccade (LatencyParams::timeline_saccade; NaN without one),
  // in every frame: before its landing the followed fovea is the saccade before's, another place
  double drawn_error = NAN;
};

// One frame of a deadline loop (wall clock): its parts, and, when it came late, where the machine's
// pause fell. The loop plans each frame to end on time: rays until a deadline (the budget less a
// margin and the composing it expects), then composing. A late frame's composing took longer than
// planned ("composing"), or its rays stopped after their deadline: the foveation maps or a planning
// pass took at least half that overrun longer than usual ("maps", "planning"), else "tracing".
struct LatencyFramePart {
  int index = 0;       // the loop's frame within the segment
  double start_s = 0;  // seconds from the recording's first sample
  double ms = 0;       // the frame's wall time
  double maps_ms = 0, plan_ms = 0, trace_ms = 0, compose_ms = 0;
  double rays_over_ms = 0;     // rays stopped this long after their deadline (0: on time)
  double compose_over_ms = 0;  // composing took this much longer than planned (0: not)
  std::string part;            // late frames: maps, planning, tracing or composing
  // Wall clock, the process's threads during the frame (NaN where they cannot be read): the longest
  // any waited, runnable, for a CPU (the kernel's run delay: a late frame with ms − cpu_wait_ms ≤
  // the budget would have been on time had this machine's kernel not kept that thread off its
  // core), the share of the wall time between the two readings around the frame that the thread
  // calling frame() was on a CPU (its maps, planning and composing run there), and the process's
  // page faults
  double cpu_wait_ms = NAN, cpu_share = NAN, faults = NAN;
  // Wall clock: the other process that ran longest during the frame, of those busiest while the
  // bench traced its references (util/cpu_share.h, threads_to_watch), and its time on a CPU ("" and 0
  // where none of them ran; NaN where not read)
  std::string other;
  double other_ms = NAN;
};
// The late frames (ms > budget_ms) of a loop's frames, each with its part (pure; tests).
std::vector<LatencyFramePart> late_frame_parts(const std::vector<LatencyFramePart>& frames, double budget_ms);
// The late frames' threads, for the bench's account: "run delay ≤ 7.9 ms (1 of 2 on time without
// it), page faults 0–3, the calling thread on a CPU 0.9–1.0 of the time; the other process busiest
// in each: kdamond.0 4.1 ms, none" ("" where none was read; pure; tests).
std::string late_threads_summary(const std::vector<LatencyFramePart>& late, double budget_ms);

struct LatencyLoop {
  std::string name;
  double budget_ms = 0;
  int frames = 0, frames_late = 0, refreshes_missed = 0;
  double frame_ms_p50 = 0, frame_ms_p99 = 0;
  double scale = 1;  // the deadline loops' resolution scale
  // Frames shown at a lowered size: each judged against references traced at the size of the view
  // it comes from (the view traced last: RealtimeLoop::traced_size; at a smaller one, references are
  // traced there on first use), on the pixels it shows, each against the references at the pixel
  // of that view whose surface it shows (RealtimeLoop::traced_pixels). Frames not judged: those
  // whose pixels the loop did not say (none expected; counted so that none goes unsaid)
  int frames_lowered = 0, frames_not_judged = 0;
  std::vector<LatencySaccade> saccades;
  std::vector<LatencyFrame> timeline;
  std::vector<LatencyFramePart> late;  // the deadline loops' late frames with where their pause fell (wall clock)
  // Wall clock, the deadline loops: frames whose rays left chunks to threads the machine had paused
  // rather than wait for them (LoopFrame::chunks_left_behind), and of those the ones that would have
  // been late had they waited (their time + LoopFrame::left_behind_ms over the budget), by up to
  int frames_left_behind = 0, late_had_they_waited = 0;
  double most_saved_ms = 0;
  std::optional<double> median_converged_ms() const;
};

struct LatencyRecording {
  std::string recording;
  double begin_s = 0, end_s = 0;  // the segment replayed, seconds from the recording's first sample
  bool cut = false;               // asked past the recording's last sample, the segment ends there
  double sampling_hz = 0, tracker_latency_ms = 0;
  double raw_rays_per_ms = 0;                        // the raw tracing rate of the run (the ray bound's denominator)
  double model_rays_per_ms = 0, model_fixed_ms = 0;  // the model clock's calibration (0 with the wall clock)
  std::vector<LatencyLoop> loops;
  std::vector<double> gaze_t;  // the segment's samples (timeline picture): time, render pixels
  std::vector<glm::dvec2> gaze_px;
  std::optional<size_t> drawn;  // the judged saccade the timeline picture draws (see LatencyParams::timeline_saccade)
};

struct LatencyReport {
  std::vector<LatencyRecording> recordings;
  std::vector<BusyProcess> others;  // the other processes that ran during the run, the busiest first (util/cpu_share.h)
  std::string markdown;
  nlohmann::json json;
};

// What the bench needs besides the recordings: the renderer on its device, the scene and camera,
// and the raw tracing rate (rays per ms) on a sample of the view's AO rays.
struct LatencyRun {
  FrameRenderer* renderer = nullptr;
  const Scene* scene = nullptr;
  Camera camera;
  std::string scene_name, device;
  std::function<double(std::span<const Ray>)> raw_rays_per_ms;
  std::function<void(const std::string&)> say;  // progress lines
};

LatencyReport run_latency_bench(const LatencyRun& run, const std::vector<Recording>& recordings, const LatencyParams& params);

// The whole bench on one device, as `bench latency` and foveal.bench_latency run it: the renderer
// (on `threads` worker threads, the caller's ThreadScope, as the report says), its raw rate, the loops on every recording, and what
// else the machine ran meanwhile (json "machine", a line under the tables). `say`: progress lines.
LatencyReport bench_latency(const Scene& scene, const std::string& scene_name, const Camera& camera, ComputeDevice device, int threads,
                            const std::vector<Recording>& recordings, const LatencyParams& params,
                            const std::function<void(const std::string&)>& say);

// The first recording's timeline picture (a run with LatencyParams::timeline_saccade): gaze x,
// the fovea's placement per frame of each loop, and the drawn saccade's fovea error per shown
// frame; written by extension (.png or .svg). Returns the saccade's index; throws Error where the
// segment has no judged saccade.
size_t write_latency_timeline(const LatencyReport& report, double min_amplitude_deg, const std::string& path);

// What to know of the drawn saccade, '' where nothing (or no timeline was drawn): that the saccade
// asked for (`asked`, LatencyParams::timeline_saccade) is past the segment's last, which is drawn
// instead; and where the drawn saccade's fovea was ready at its landing in every deadline loop, so
// that its picture shows no wait, the saccade the first deadline loop waited longest for (one that
// never converged within the segment counts as longest) with the option that draws it (`option`:
// "--timeline-saccade ", or Python's "timeline_saccade=").
std::string latency_timeline_note(const LatencyReport& report, size_t asked, const std::string& option);

}  // namespace foveal
