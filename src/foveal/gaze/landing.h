// foveal/gaze/landing.h — where and when a saccade will land, from its first samples.
//
// A causal predictor for a live sample stream: it detects a saccade's onset, predicts its landing
// position and time while the eye is in flight, refines the prediction with every sample, and
// reports the measured landing once the eye has stopped (a wrong prediction is then abandoned).
//
// The model is the saccade's ballistic velocity profile. A saccade accelerates to a peak velocity
// and decelerates to rest along a nearly straight path; its profile is close to symmetric in time
// for small saccades and skewed (a longer deceleration) for large ones (Van Opstal & Van Gisbergen
// 1987, "Skewness of saccadic velocity profiles: a unifying parameter for normal and slow
// saccades", Vision Research 27(5)). Mirroring the profile about its peak gives the rest of the
// flight from its start: after the peak, the distance still to go from a velocity v is what the
// acceleration covered up to v, stretched by the skew, and likewise the time. Before the peak
// (no deceleration seen yet) the landing is at least twice the distance travelled. The duration is
// bounded by the main sequence D = 21 ms + 2.2 ms/° · A (Carpenter 1988, "Movements of the
// eyes", 2nd ed.; Baloh et al. 1975) so that a sample stream that never decelerates (a pursuit, a
// drift) is not held for a saccade. Arabadzhiyska et al. (2017, "Saccade landing position
// prediction for gaze-contingent rendering", ACM TOG 36(4)) fit a per-user model of the same
// profile; this one needs no calibration, and docs/realtime.md gives its error on expert-labelled
// saccades.
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace foveal {

// The slowest sample stream the predictor can follow: a saccade's onset needs two samples above
// its onset velocity within the saccade's first tens of milliseconds, so under 20 Hz (samples more
// than 50 ms apart) no saccade is seen and no landing predicted.
inline constexpr double kSlowestLandingSampleS = 0.05;

// Samples further apart than this (under 90 Hz) show a saccade in a few: its onset is seen late, and
// a landing predicted then is too late to gain much, even a perfect prediction. On Lund 2013's
// training recordings (their saccades of 5° or more, `bench/landing_rays.py --sample-hz`, a 60-Hz
// display) a perfect predictor put 3.3 points more of a landed fovea's rays there before the
// landing than none at 500 Hz, 1.1 at 100 Hz, 0.4 at 83 Hz, 0.1 at 62 Hz; the loop's predictor
// 0.54, 0.33, 0.14 and 0.05 (docs/realtime.md).
inline constexpr double kLateLandingSampleS = 1.0 / 90;

// Why samples `interval_s` apart (their median) show the predictor nothing, in words: "" where they
// come at 20 Hz or faster; else "under 20 Hz no saccade is seen, and no landing predicted", and
// from half a second apart what most often causes that: times in milliseconds, where `reader` (the
// caller: "the loop", "bench latency", …) takes seconds.
std::string unseen_saccades_note(double interval_s, const std::string& reader);

// What samples at `sample_hz` leave the predictor to gain, in words: "" where they come at 90 Hz
// or faster, or too slowly to be followed at all (under 20 Hz: kSlowestLandingSampleS, said apart),
// or at no rate (0: fewer than two).
std::string late_landing_note(double sample_hz);

struct LandingParams {
  double onset_deg_s = 40;      // a velocity above this (two samples in a row) starts a saccade
  double offset_deg_s = 30;     // the saccade ends when the velocity falls below this
  double min_flight_deg = 0.5;  // shorter flights (onset to measured landing) are not reported as saccades
  // The profile's skew (deceleration / acceleration; 1 = symmetric) grows with the amplitude (Van
  // Opstal & Van Gisbergen 1987): skew + skew_per_deg · A, A the symmetric mirror's amplitude, at
  // most max_skew. Chosen on Lund 2013's training recordings (landing_test.cpp's grid: the error
  // two thirds into each labelled saccade; 1 + 0.03/° is within 5 % of the best median there and
  // keeps the growth the literature reports, which those mostly small saccades barely show)
  double skew = 1.0;
  double skew_per_deg = 0.03;
  double max_skew = 4;
  double peak_drop = 0.8;            // the peak is taken as passed once the velocity is below this fraction of it
  double max_velocity_deg_s = 1000;  // faster sample-to-sample velocities are noise (ignored)
  double main_sequence_ms = 21, main_sequence_ms_per_deg = 2.2;  // D = a + b·A (Carpenter 1988)
  // The peak velocity's main sequence V = V_max·(1 − exp(−A/C)) (Baloh et al. 1975): a flight longer
  // than slack × D of the amplitude its peak velocity implies is no saccade (a pursuit, a drift)
  double main_sequence_vmax_deg_s = 500, main_sequence_c_deg = 14;
  double duration_slack = 3.0;
};
// Check the parameters; throws Error naming the field.
void validate(const LandingParams& params);
// Set one parameter by its field's name (onset_deg_s, …, duration_slack); throws Error naming an
// unknown one and the known.
void set_landing_parameter(LandingParams& params, const std::string& name, double value);
// Every parameter by name, in the order of LandingParams (what a run used, for its report).
std::vector<std::pair<std::string, double>> landing_parameters(const LandingParams& params);
// "NAME=VALUE[,NAME=VALUE…]" over `base` (blank: `base` itself), checked (the command line's
// --landing); throws Error naming the part that is wrong.
LandingParams parse_landing_params(const std::string& text, LandingParams base = {});

// What the predictor knows at the latest sample.
struct LandingState {
  bool in_flight = false;          // a saccade is under way
  bool past_peak = false;          // its peak velocity has been seen
  double onset_s = 0;              // the saccade's start (the last sample before the threshold crossing)
  glm::dvec2 onset_deg{0};         // where it started
  glm::dvec2 landing_deg{0};       // predicted landing position (in flight) or the measured one
  double landing_s = 0;            // predicted landing time (in flight) or the measured one
  double amplitude_deg = 0;        // predicted amplitude
  double peak_velocity_deg_s = 0;  // so far
};

// One saccade as the predictor saw it, for evaluation (gaze --events, bench latency).
struct PredictedSaccade {
  double onset_s = 0;                 // detected start
  double detected_s = 0;              // the sample at which the onset was detected
  double first_prediction_s = 0;      // the first sample past the peak (the first mirrored prediction)
  glm::dvec2 first_landing_deg{NAN};  // the prediction made then
  double first_landing_time_s = NAN;
  double settled_s = NAN;     // from here on every prediction was within 1° of the landing (NaN: never)
  double landing_s = 0;       // measured landing (the first sample below the offset threshold)
  glm::dvec2 landing_deg{0};  // measured landing position
  double amplitude_deg = 0;   // measured
  // Every prediction of the flight, in time order (the sample's time and the predicted landing)
  std::vector<double> prediction_s;
  std::vector<glm::dvec2> prediction_deg;
  // The prediction in force at time t (NaN before the first)
  glm::dvec2 prediction_at(double t_s) const;
};

class LandingPredictor {
 public:
  // `keep_saccades`: keep every landed saccade with its predictions (saccades(), for evaluation); a
  // live loop does not, so that a session of hours holds no growing history
  explicit LandingPredictor(const LandingParams& params = {}, bool keep_saccades = false);
  // The next sample, in time order: position in degrees (any fixed planar frame: x right, y up or
  // down), valid false for a lost sample (which ends a flight without a landing).
  void push(double t_s, glm::dvec2 deg, bool valid = true);
  const LandingState& state() const { return state_; }
  // Saccades that have landed since the start (with the prediction history of each), where kept.
  const std::vector<PredictedSaccade>& saccades() const { return done_; }
  void reset();

 private:
  struct Profile {
    double t = 0, distance = 0, velocity = 0;
  };
  void start(double t_s, glm::dvec2 from);
  void predict(double t_s, glm::dvec2 deg, double velocity);
  void land(double t_s, glm::dvec2 deg);
  void abandon();

  struct Sample {
    double t = 0;
    glm::dvec2 deg{0};
  };
  LandingParams params_;
  bool keep_saccades_ = false;
  LandingState state_;
  std::vector<Sample> history_;  // the samples of the velocity baseline
  Sample onset_candidate_;       // where the first fast sample's baseline started
  int fast_run_ = 0;
  double slow_since_ = NAN;    // since when the velocity is below the peak drop
  double sample_period_ = 0;   // the latest interval
  std::vector<Profile> rise_;  // acceleration phase: time, distance, velocity since onset
  PredictedSaccade current_;
  std::vector<glm::dvec2> predictions_;  // every prediction of the current flight (for settled_s)
  std::vector<double> prediction_t_;
  std::vector<PredictedSaccade> done_;
};

// Each detected saccade's landing as the predictor would have predicted it live (gaze --events):
// the predictor runs causally over the recording, and the flight whose onset lies within a
// detected saccade (from 20 ms before it) is its prediction.
struct LandingReport {
  size_t event = 0;                   // index into the detection's events
  double onset_s = 0, landing_s = 0;  // the detected saccade's, seconds from the recording's first sample
  double amplitude_deg = 0;           // the detected saccade's
  glm::dvec2 landing_deg{NAN};        // where it ended (the detection's end position)
  bool predicted = false;             // the predictor saw the flight
  glm::dvec2 first_deg{NAN};          // its first prediction past the peak
  double first_error_deg = NAN;
  glm::dvec2 two_thirds_deg{NAN};  // the prediction in force two thirds into the saccade
  double two_thirds_error_deg = NAN;
  double gained_ms = NAN;  // landing − the time from which every prediction was within 1°
};
struct EventDetection;
class GazeGeometry;
struct Recording;
std::vector<LandingReport> evaluate_landings(const Recording& recording, const GazeGeometry& geometry, const EventDetection& detection,
                                             const LandingParams& params = {});
// The reports as a tab-separated table (one row per detected saccade; n/a where not predicted).
std::string landings_tsv(const std::vector<LandingReport>& reports);

// Run the predictor over a whole sample stream (positions in degrees; NaN = lost) and return the
// saccades it saw.
std::vector<PredictedSaccade> predict_landings(const std::vector<double>& t_s, const std::vector<glm::dvec2>& deg,
                                               const LandingParams& params = {});

}  // namespace foveal
