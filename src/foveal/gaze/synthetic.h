// foveal/gaze/synthetic.h — synthetic eye-movement recordings with known events.
//
// A horizontal gaze signal built from segments, each with its true label per sample:
//   fixations (the eye still; the tracker's noise added later);
//   saccades: minimum-jerk position profiles (Flash & Hogan 1985) with the main sequence's
//     duration, 2.2 ms/° + 21 ms (Carpenter 1988, "Movements of the Eyes", 2nd ed., p. 72);
//   post-saccadic oscillations: a damped 40 Hz wobble after the saccade (Hooge, Nyström, Cornelissen
//     & Holmqvist 2015: 20–60 Hz, decaying within tens of milliseconds), labelled PSO for 25 ms;
//   smooth pursuit: a constant-velocity ramp;
//   blinks: lost samples.
// recording() adds white noise of a given 2-D RMS and bursts of lost samples (a tracker losing the
// pupil), so that a detector can be scored against the truth under known degradation.
#pragma once

#include "foveal/gaze/events.h"

#include <vector>

namespace foveal {

struct SyntheticEvent {
  EventLabel label;
  double onset_s, duration_s, amplitude_deg;
};

struct SyntheticSignal {
  explicit SyntheticSignal(double rate_hz = 1000, double start_deg = 0);
  double rate_hz;
  std::vector<double> x;              // degrees from the screen centre along the horizontal, NaN = lost
  std::vector<EventLabel> label;      // the truth per sample
  std::vector<SyntheticEvent> truth;  // the events (saccades, PSOs, pursuits, blinks), onsets from the first sample

  void fixation(double seconds);
  void saccade(double amplitude_deg, double pso_deg = 0);
  void pursuit(double deg_per_s, double seconds);
  void blink(double seconds);

  struct Degradation {
    double noise_rms_deg = 0.05;  // 2-D RMS of white noise on every sample
    double loss_fraction = 0;     // share of samples lost, in bursts …
    double burst_s = 0.010;       // … of about this length (uniform in [0.5, 1.5]×: dropouts of a few samples), placed at random
    unsigned seed = 7;
  };
  // The samples (directions through the display of make_synthetic_geometry), t from `t0_s`, and
  // the truth per sample (lost samples keep the label of what the eye was doing).
  Recording recording(const Degradation& degradation, double t0_s = 100) const;
};

// A free-viewing sequence of about `seconds`: fixations of 150–400 ms, saccades of 1–15°
// (log-uniform; every other one with a PSO), and, where `with_pursuit`, pursuits of 4–15 °/s over
// 300–800 ms followed by a catch-up saccade of 1–2.5° and 300 ms more; a blink every 3 s.
// Deterministic for a seed.
SyntheticSignal synthetic_viewing(double seconds, double rate_hz, bool with_pursuit, unsigned seed);

// The display the synthetic recordings are in (53.3 × 30.1 cm at 56.5 cm, 1920 × 1080: the IRF set's).
Display synthetic_display();

}  // namespace foveal
