// foveal/gaze/detect.h — eye-movement event detectors over one sample representation.
//
// Every detector works on the same thing: the recording's valid samples as unit gaze directions
// (GazeGeometry: the display's physical size and distance, or the tracker's own 3-D direction),
// so velocities and amplitudes are exact visual angles — the angular speed of a unit vector d is
// |dd/dt|, the amplitude of an event the angle between its first and last direction.
//
//   ivt, idt  the fixation filters of fixation.h; their other valid samples are saccades, lost
//             samples blinks (the baseline).
//   ek        Engbert & Kliegl (2003, "Microsaccades uncover the orientation of covert attention",
//             Vision Research 43:1035–1045): velocities from a 5-sample moving window, a threshold
//             per axis of λ times the median-based standard deviation, a sample is saccadic when it
//             lies outside the ellipse (vx/ηx)² + (vy/ηy)² > 1 for at least the minimum duration;
//             the rest of the valid samples fixations.
//   nh        Nyström & Holmqvist (2010, "An adaptive algorithm for fixation, saccade, and glissade
//             detection in eyetracking data", Behavior Research Methods 42:188–204): Savitzky–Golay
//             velocity and acceleration (order 2), physiologically impossible samples as noise, a
//             peak threshold found from the data (PT = μ + 6σ of the samples below PT, iterated from
//             100 °/s), onsets where the velocity before a peak falls below μ + 3σ, offsets where
//             it falls below 0.7·(μ + 3σ) + 0.3·(the local noise of the 40 ms before the onset) or
//             at the first velocity trough under PT, post-saccadic oscillations (PSO, "glissades")
//             as velocity above the offset threshold again within 40 ms of an offset; fixations of
//             at least 40 ms. Departures from the paper, each measured on the IRF recordings
//             (docs/gaze.md): a 6 ms filter window instead of 20 ms (twice the minimum saccade: it
//             smears the saccade's edges over 1000 Hz EyeLink data), threshold crossings instead of
//             local minima for the onset, the trough rule for the offset, a second, smoother
//             velocity (a least-squares line over 20 ms, its own μ + 6σ) whose peaks also start
//             saccades (microsaccades in noise), a minimum saccade of 8 ms instead of 10, and
//             saccades or PSOs within 25 ms of a blink taken into it (the lid's movement).
//   nhp       nh, then smooth pursuit in the intersaccadic intervals (the second stage of I-VDT,
//             Komogortsev & Karpov 2013, with a velocity rather than a dispersion test, as REMoDNaV
//             does): the velocity of a least-squares line over a longer window; samples faster than
//             the pursuit threshold for the minimum pursuit duration, covering at least half the
//             distance that speed implies, are pursuit.
//   nhr       the recommended detector (auto): nh's saccades and PSOs on local, robust thresholds
//             (median + k·MAD of a 0.5 s window; Engbert & Kliegl's estimator, REMoDNaV's windows),
//             a 10 ms filter, a saccade's first sample the first above the onset threshold, PSOs
//             within 20 ms of the offset, dropouts filled, and smooth pursuit inside each
//             intersaccadic interval and in context across catch-up saccades (in the spirit of
//             Larsson et al. 2015). Each departure and what it measured: docs/gaze.md.
//
// Blinks (ek, nh, nhp): a run of lost samples, widened on both sides over the lid's artefacts —
// samples whose velocity stays above the detector's onset threshold, whose velocity or
// acceleration is impossible, or whose pupil (where the tracker gives one) is far from the
// recording's median — up to a limit either side. Lost runs longer than the longest blink are
// undefined (the eye left the tracker).
#pragma once

#include "foveal/gaze/events.h"

#include <optional>
#include <string>
#include <vector>

namespace foveal {

enum class EventMethod { ivt, idt, ivvt, ek, nh, nhp, nhr };
inline constexpr EventMethod kRecommendedEventMethod = EventMethod::nhr;
const char* to_string(EventMethod method);
// ivt, idt, ivvt, ek, nh, nhp, nhr or auto (the recommended); throws Error naming --events.
EventMethod parse_event_method(const std::string& name);

struct EventParams {
  // Blinks
  double blink_flank_s = 0.100;   // the lid's artefacts either side of a loss: at most this long
  double max_blink_s = 2.0;       // longer losses are undefined, not blinks
  double pupil_deviation = 0.25;  // a pupil this far (relative) from the median is the lid's
  double lid_saccade_s = 0.025;   // nh, nhp: a saccade or PSO this close to a blink is the lid's (part of the blink)
  // Nyström & Holmqvist 2010
  double filter_window_s = 0.006;     // Savitzky–Golay window (the paper: 20 ms; see above)
  double detection_window_s = 0.020;  // a smoother velocity (least-squares line) whose own peaks also start saccades (0: off)
  double initial_peak_deg_s = 100;    // where the peak threshold's iteration starts
  double max_velocity_deg_s = 1000;   // faster samples are noise
  double max_acceleration_deg_s2 = 100000;
  double min_saccade_s = 0.008;   // the paper: 10 ms (see above)
  double min_fixation_s = 0.040;  // shorter intersaccadic runs are undefined
  double pso_window_s = 0.040;    // a PSO begins within this time of a saccade's offset
  double local_noise_s = 0.040;   // the window before an onset that sets the offset threshold
  // Engbert & Kliegl 2003
  double ek_lambda = 6;
  double ek_min_saccade_s = 0.006;
  PursuitParams pursuit;  // nhp: smooth pursuit in the intersaccadic intervals
  // nhr (tuned on the IRF recordings and the Lund 2013 training recordings only; docs/gaze.md)
  double max_dropout_s = 0.025;           // shorter losses are the tracker's dropouts, not blinks: filled in between their neighbours
  double robust_filter_window_s = 0.010;  // Savitzky–Golay window of the velocity
  double threshold_window_s = 0.5;        // local thresholds: the median and MAD of this window's velocities …
  double robust_peak_k = 8;               // … peak threshold median + k·1.4826·MAD
  double robust_onset_k = 4.5;            // … onset threshold median + k·1.4826·MAD
  double robust_pso_window_s = 0.020;     // a PSO begins within this time of the saccade's offset (nh: pso_window_s, 40 ms)
  double min_peak_deg_s = 10;             // floors (a noise-free recording's MAD is 0; nh, nhp too): the peak's, half of it the onset's
  // A saccade ends at its first velocity trough below this fraction of its peak velocity (0, and nh:
  // below the peak threshold)
  double saccade_trough = 0.25;
  PursuitParams slow_pursuit{2.5, 0.400, 0.200, 0.5};  // speed of a line over the window, inside one intersaccadic interval
  double pursuit_keep = 0.7;                           // a pursuit goes on while its speed stays above this fraction of the threshold
  double pursuit_edge_s = 0.100;       // … and a pursuit's edges are where a line over this window passes it (0: the window's)
  double settle_s = 0.050;             // the eye settling after a saccade: not counted toward a pursuit's duration
  double context_s = 0.100;            // a pursuit this close (across a saccade and its PSO) …
  double context_relax = 0.4;          // … lowers the speed threshold by this factor …
  double context_min_fraction = 0.25;  // … and the minimum duration by this one, for movement the same way:
  double context_cos = 0.7;            // within acos(0.7) = 46° of that pursuit's direction
};
// Check parameters; throws Error naming the option.
void validate(const EventParams& params);

// One event: a run of samples with one label.
struct DetectedEvent {
  EventLabel label = EventLabel::undefined;
  size_t first = 0, last = 0;               // sample indices, inclusive
  double onset_s = 0, duration_s = 0;       // first sample's time; time to the sample after the last (one sample: one interval)
  double amplitude_deg = 0;                 // angle between the first and last valid direction (NaN for blinks)
  double peak_velocity_deg_s = 0;           // largest velocity inside (NaN where none)
  glm::dvec2 start_deg{NAN}, end_deg{NAN};  // first/last valid position, degrees from the screen centre, x right, y up
};

struct EventDetection {
  std::optional<EventMethod> method;  // none: labels from elsewhere (events_from_labels)
  std::vector<EventLabel> labels;     // per sample
  std::vector<DetectedEvent> events;  // the runs of labels, undefined runs left out
  std::vector<float> velocity_deg_s;  // per sample (NaN where the eye was lost)
  double sampling_hz = 0;             // the median interval's rate
  double peak_threshold_deg_s = NAN;  // nh/nhp: the adaptive thresholds found; ek: the mean of ηx, ηy
  double onset_threshold_deg_s = NAN;
};

// Detect events over a whole recording (offline). `fixation` parametrises ivt and idt.
EventDetection detect_events(const Recording& recording, const GazeGeometry& geometry, EventMethod method, const EventParams& params,
                             const FixationParams& fixation);

// Events, amplitudes and peak velocities for labels from elsewhere (another tool's, a coder's).
EventDetection events_from_labels(const Recording& recording, const GazeGeometry& geometry, std::vector<EventLabel> labels);

// The events as a BIDS-style events table (tab-separated, header onset, duration, trial_type,
// amplitude_deg, peak_velocity_deg_s, start_x_deg, start_y_deg, end_x_deg, end_y_deg; n/a where
// undefined); onsets in seconds from the recording's first sample.
std::string events_tsv(const EventDetection& detection, const Recording& recording);

// The thresholds of Nyström & Holmqvist's iteration over velocities (NaN entries ignored): returns
// {peak, onset} = {μ + 6σ, μ + 3σ} of the samples below the converged peak threshold.
std::pair<double, double> adaptive_velocity_thresholds(const std::vector<float>& velocity_deg_s, double initial_peak_deg_s);

}  // namespace foveal
