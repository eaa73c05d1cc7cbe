// foveal/experiments/event_degradation.h — event detectors under known degradation.
//
// A minute of synthetic free viewing with pursuit (gaze/synthetic.h: known events) per sampling
// rate, degraded by white noise of a given RMS and bursts of lost samples, labelled by each
// detector and scored against the truth with the same code as against human coders (events.h:
// sample κ per class, event F1 with Hooge et al. 2018's matching). `foveal bench events`.
#pragma once

#include "foveal/gaze/detect.h"

#include <string>
#include <vector>

namespace foveal {

struct DegradationParams {
  double seconds = 60;
  std::vector<double> rates_hz{250, 500, 1000, 2000};
  std::vector<double> noise_rms_deg{0.02, 0.05, 0.1, 0.2, 0.3};
  std::vector<double> loss_fractions{0, 0.05, 0.10, 0.15};
  double burst_s = 0.010;  // lost bursts of 5–15 ms (the tracker's dropouts; blinks are in the signal)
  std::vector<EventMethod> methods{EventMethod::nhr, EventMethod::nhp};
  unsigned seed = 11;
};
// Throws Error naming the parameter.
void validate(const DegradationParams& params);

struct DegradationRow {
  double rate_hz = 0, noise_rms_deg = 0, loss_fraction = 0;
  EventMethod method = EventMethod::nhr;
  double saccade_f1 = 0, saccade_kappa = 0, pso_kappa = 0, fixation_kappa = 0, pursuit_kappa = 0, pursuit_f1 = 0;
  size_t samples = 0, saccades = 0;  // of the truth
};

std::vector<DegradationRow> run_event_degradation(const DegradationParams& params);

// Markdown: one table per detector, rows noise × loss, columns saccade event F1 per rate; then the
// pursuit κ the same way.
std::string degradation_markdown(const DegradationParams& params, const std::vector<DegradationRow>& rows);

}  // namespace foveal
