// foveal/gaze/steps.cpp — fixations of recorded or live gaze as simulation steps.
#include "foveal/gaze/steps.h"

#include "foveal/gaze/detect.h"
#include "foveal/util/error.h"

#include <chrono>
#include <cmath>
#include <thread>

namespace foveal {

StepFixations parse_step_fixations(const std::string& name) {
  if (name == "nhr" || name == "auto") return StepFixations::nhr;
  if (name == "nhp") return StepFixations::nhp;
  if (name == "ivt") return StepFixations::ivt;
  if (name == "idt") return StepFixations::idt;
  if (name == "tracker") return StepFixations::tracker;
  if (name == "mean")
    fail("fixation: 'mean' gives a gaze point per frame, not fixations; simulate steps from fixation to fixation: use ivt, idt or tracker");
  fail("fixation: unknown filter '{}' (auto = nhr, nhp, ivt, idt or tracker: the recording's own fixation events)", name);
}

const char* to_string(StepFixations source) {
  switch (source) {
    case StepFixations::nhr:
      return "nhr";
    case StepFixations::nhp:
      return "nhp";
    case StepFixations::ivt:
      return "ivt";
    case StepFixations::idt:
      return "idt";
    case StepFixations::tracker:
      return "tracker";
  }
  return "?";
}

FixationMethod live_filter(StepFixations source) {
  switch (source) {
    case StepFixations::nhr:
    case StepFixations::nhp:
      return FixationMethod::ivvt;
    case StepFixations::ivt:
      return FixationMethod::ivt;
    case StepFixations::idt:
      return FixationMethod::idt;
    case StepFixations::tracker:
      break;
  }
  fail("fixation: a live tracker sends gaze, not fixation events: use auto, ivt or idt");
}

std::vector<GazeEvent> invalid_gap_blinks(const std::vector<GazeSample>& samples) {
  std::vector<GazeEvent> blinks;
  double last_valid = NAN;
  bool gap = false;
  for (const GazeSample& s : samples) {
    if (!s.valid) {
      gap = true;
      continue;
    }
    if (gap && std::isfinite(last_valid) && blink_gap(last_valid, s.t_s)) blinks.push_back({last_valid, s.t_s, glm::dvec2(NAN)});
    gap = false;
    last_valid = s.t_s;
  }
  return blinks;
}

std::vector<GazeStep> recording_steps(const Recording& r, const GazeGeometry& geometry, StepFixations source,
                                      const FixationParams& params) {
  std::vector<GazeEvent> fixations, detected_blinks;
  switch (source) {
    case StepFixations::nhr:
    case StepFixations::nhp: {
      EventParams ep;
      ep.pursuit = params.pursuit;
      const EventDetection d = detect_events(r, geometry, source == StepFixations::nhr ? EventMethod::nhr : EventMethod::nhp, ep, params);
      for (const DetectedEvent& e : d.events) {
        const double end_s = r.samples[e.last].t_s;
        if (e.label == EventLabel::fixation) {
          glm::dvec2 sum(0);
          size_t count = 0;
          for (size_t i = e.first; i <= e.last; ++i)
            if (r.samples[i].valid) sum += r.samples[i].px, ++count;
          if (count) fixations.push_back({r.samples[e.first].t_s, end_s, sum / static_cast<double>(count)});
        } else if (e.label == EventLabel::pursuit) {
          // The fovea moves with the eye: a step every pursuit_step_s, where the eye is then
          size_t i = e.first;
          for (double t = r.samples[e.first].t_s; t < end_s; t += pursuit_step_s) {
            while (i < e.last && (r.samples[i].t_s < t || !r.samples[i].valid)) ++i;
            if (r.samples[i].valid) fixations.push_back({t, std::min(t + pursuit_step_s, end_s), r.samples[i].px});
          }
        } else if (e.label == EventLabel::blink) {
          detected_blinks.push_back({r.samples[e.first].t_s, end_s, glm::dvec2(NAN)});
        }
      }
      break;
    }
    case StepFixations::ivt:
    case StepFixations::idt: {
      const FixationResult result = source == StepFixations::ivt ? detect_ivt(r, geometry, params) : detect_idt(r, geometry, params);
      for (const Fixation& f : result.fixations) fixations.push_back({f.start_s, f.end_s, f.px});
      break;
    }
    case StepFixations::tracker:
      if (r.fixations.empty())
        fail("{}: fixation tracker: the recording has no fixation events of its tracker{} (use ivt or idt)", r.source,
             r.has_tracker_fixations ? "" : fmt::format(" ({} exports none)", r.tracker));
      fixations = r.fixations;
      break;
  }
  const std::vector<GazeEvent> blinks = !r.blinks.empty()                                              ? r.blinks
                                        : source == StepFixations::nhp || source == StepFixations::nhr ? detected_blinks
                                                                                                       : invalid_gap_blinks(r.samples);
  std::vector<GazeStep> steps;
  double previous_end = -INFINITY;
  size_t b = 0;
  for (const GazeEvent& f : fixations) {
    if (!std::isfinite(f.px.x) || !std::isfinite(f.px.y)) continue;
    GazeStep step{f.px, f.start_s, f.end_s - f.start_s, false};
    // A blink that overlaps the time since the previous fixation ended
    while (b < blinks.size() && blinks[b].end_s <= previous_end) ++b;
    step.blink_before = !steps.empty() && b < blinks.size() && blinks[b].start_s < f.start_s;
    steps.push_back(step);
    previous_end = std::max(previous_end, f.end_s);
  }
  return steps;
}

LiveSteps::LiveSteps(GazeSource& source, FixationMethod method, const FixationParams& params, const GazeGeometry& geometry)
    : source_(source), tracker_(method, params, geometry) {
  if (method == FixationMethod::mean) fail("fixation: live steps need fixations (ivt or idt), not the per-frame mean");
}

std::optional<GazeStep> LiveSteps::next(double timeout_s) {
  for (;;) {
    while (pending_at_ < pending_.size()) {
      const GazeSample& s = pending_[pending_at_++];
      ++samples_;
      if (!s.valid) {
        if (std::isnan(invalid_since_)) invalid_since_ = std::isfinite(last_valid_t_) ? last_valid_t_ : s.t_s;
      } else {
        if (!std::isnan(invalid_since_)) {
          blink_ = blink_ || blink_gap(invalid_since_, s.t_s);
          invalid_since_ = NAN;
        }
        last_valid_t_ = s.t_s;
      }
      tracker_.push(s);
      const bool fixating = tracker_.in_fixation();
      const bool onset = fixating && !was_fixating_;
      was_fixating_ = fixating;
      if (onset && tracker_.current()) {
        GazeStep step{*tracker_.current(), s.t_s, 0, blink_};
        blink_ = false;
        return step;
      }
    }
    pending_.clear();
    pending_at_ = 0;
    source_.poll(pending_);
    if (!pending_.empty()) continue;
    const SourceState state = source_.state();
    if (state == SourceState::disconnected || state == SourceState::ended) {
      // A source turns disconnected or ended only after handing over what it had: take it
      source_.poll(pending_);
      if (!pending_.empty()) continue;
      why_ = fmt::format("{}: {} after {} samples", source_.name(), to_string(state), samples_);
      return std::nullopt;
    }
    if (source_.silent_s() > timeout_s) {
      why_ = fmt::format("{}: no gaze for {:.1f} s (tracker silent) after {} samples", source_.name(), source_.silent_s(), samples_);
      return std::nullopt;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

}  // namespace foveal
