// foveal/gaze/steps.h — real eye movements as the vision simulation's time steps.
//
// The simulation's time step is one fixation (the second paper's loop). A recording gives its
// fixations from the recommended event detector (auto = nhr, or nhp: its fixations, and a step
// every 100 ms of a smooth pursuit, whose fovea moves), a filter (I-VT, I-DT) or the tracker's own
// fixation events; a live tracker gives one each time its causal filter (nhr, nhp: I-VVT)
// establishes a new fixation. A blink between two fixations makes
// the sharpness field forget: the tracker's own blink events where the recording has them, else
// a run of invalid samples lasting a blink's duration (70–500 ms; shorter runs are lost samples,
// longer ones the eye leaving the tracker).
#pragma once

#include "foveal/gaze/fixation.h"
#include "foveal/gaze/source.h"

#include <optional>
#include <string>
#include <vector>

namespace foveal {

// Where the steps' fixations come from.
enum class StepFixations { nhr, nhp, ivt, idt, tracker };
StepFixations parse_step_fixations(const std::string& name);  // throws Error naming --fixation
const char* to_string(StepFixations source);
// The causal filter whose fixation onsets are a live tracker's steps (nhr, nhp: I-VVT); throws Error
// for `tracker`, which a live tracker does not send.
FixationMethod live_filter(StepFixations source);

struct GazeStep {
  glm::dvec2 screen_px{0};    // fixation centre, the recording's screen pixels
  double start_s = 0;         // tracker clock, seconds
  double duration_s = 0;      // 0 for live fixations (not over yet when the step runs)
  bool blink_before = false;  // the eye blinked since the previous fixation
};

// A pursuit becomes a step every this long.
inline constexpr double pursuit_step_s = 0.100;

// Blink durations: a run of invalid samples within these bounds is a blink.
inline constexpr double min_blink_s = 0.070, max_blink_s = 0.500;
// Whether a run of invalid samples from the last valid sample at `from_s` to the next at `to_s` is a blink.
inline bool blink_gap(double from_s, double to_s) { return to_s - from_s >= min_blink_s && to_s - from_s <= max_blink_s; }

// The fixations of a recording as steps, in time order (fixations without a finite centre are
// dropped). `tracker` needs the recording's own fixation events; throws Error when it has none.
std::vector<GazeStep> recording_steps(const Recording& recording, const GazeGeometry& geometry, StepFixations source,
                                      const FixationParams& params);

// Runs of invalid samples of a blink's duration, as [start, end] times (the last valid sample
// before and the first after).
std::vector<GazeEvent> invalid_gap_blinks(const std::vector<GazeSample>& samples);

// Fixations from a live source: next() polls (without blocking the source) until the causal filter
// establishes a new fixation, the source has been silent for `timeout_s`, or it disconnects.
class LiveSteps {
 public:
  LiveSteps(GazeSource& source, FixationMethod method, const FixationParams& params, const GazeGeometry& geometry);
  // The next fixation, or nullopt with why() set.
  std::optional<GazeStep> next(double timeout_s);
  const std::string& why() const { return why_; }
  size_t samples() const { return samples_; }

 private:
  GazeSource& source_;
  FixationTracker tracker_;
  std::vector<GazeSample> pending_;  // polled but not yet pushed (after a fixation began)
  size_t pending_at_ = 0;
  bool was_fixating_ = false;
  double last_valid_t_ = NAN, invalid_since_ = NAN;
  bool blink_ = false;
  size_t samples_ = 0;
  std::string why_;
};

}  // namespace foveal
