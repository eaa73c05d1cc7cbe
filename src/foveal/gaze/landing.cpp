// foveal/gaze/landing.cpp — causal saccade landing prediction (the mirrored velocity profile).
#include "foveal/gaze/landing.h"

#include "foveal/gaze/detect.h"
#include "foveal/gaze/fixation.h"
#include "foveal/util/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace foveal {

namespace {

// Velocities are taken over at least this long a baseline (one sample where samples are further
// apart): at 1000 Hz a single interval turns 0.05° of noise into 70°/s, over 4 ms into 18°/s.
constexpr double kVelocityBaselineS = 0.004;

}  // namespace

std::string unseen_saccades_note(double interval_s, const std::string& reader) {
  if (!(interval_s > kSlowestLandingSampleS)) return "";
  return fmt::format("under 20 Hz no saccade is seen, and no landing predicted{}",
                     interval_s >= 0.5 ? "; are the times in milliseconds? " + reader + " takes seconds" : "");
}

std::string late_landing_note(double sample_hz) {
  if (!(sample_hz < 1 / kLateLandingSampleS && sample_hz >= 1 / kSlowestLandingSampleS)) return "";
  return fmt::format(
      "gaze samples come {:.3g} ms apart ({:.0f} Hz): a saccade spans only a few, its onset is seen late, and under 90 Hz a "
      "predicted landing comes too late to gain much",
      1000 / sample_hz, sample_hz);
}

void validate(const LandingParams& p) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) fail("{}: must be > 0, got {}", name, v);
  };
  positive(p.onset_deg_s, "onset_deg_s");
  positive(p.offset_deg_s, "offset_deg_s");
  positive(p.max_velocity_deg_s, "max_velocity_deg_s");
  positive(p.duration_slack, "duration_slack");
  positive(p.main_sequence_ms_per_deg, "main_sequence_ms_per_deg");
  positive(p.main_sequence_vmax_deg_s, "main_sequence_vmax_deg_s");
  positive(p.main_sequence_c_deg, "main_sequence_c_deg");
  if (!(p.min_flight_deg >= 0)) fail("min_flight_deg: must be >= 0, got {}", p.min_flight_deg);
  if (!(p.skew >= 0.25 && p.skew <= 4)) fail("skew: must be in [0.25, 4], got {}", p.skew);
  if (!(p.skew_per_deg >= 0 && p.skew_per_deg <= 1)) fail("skew_per_deg: must be in [0, 1], got {}", p.skew_per_deg);
  if (!(p.max_skew >= p.skew && p.max_skew <= 8)) fail("max_skew: must be in [skew, 8], got {}", p.max_skew);
  if (!(p.peak_drop > 0 && p.peak_drop < 1)) fail("peak_drop: must be in (0, 1), got {}", p.peak_drop);
  if (!(p.main_sequence_ms >= 0)) fail("main_sequence_ms: must be >= 0, got {}", p.main_sequence_ms);
  if (p.offset_deg_s > p.onset_deg_s) fail("offset_deg_s: must be <= onset_deg_s = {}, got {}", p.onset_deg_s, p.offset_deg_s);
  // Samples faster than max_velocity_deg_s are dropped as tracker noise, so an onset at or above it would
  // never be crossed: the predictor would find no saccade, without a word.
  if (p.onset_deg_s >= p.max_velocity_deg_s)
    fail("onset_deg_s: must be < max_velocity_deg_s = {} (faster samples are dropped as noise, so no saccade would start), got {}",
         p.max_velocity_deg_s, p.onset_deg_s);
}

namespace {

constexpr std::pair<const char*, double LandingParams::*> kLandingFields[] = {
    {"onset_deg_s", &LandingParams::onset_deg_s},
    {"offset_deg_s", &LandingParams::offset_deg_s},
    {"min_flight_deg", &LandingParams::min_flight_deg},
    {"skew", &LandingParams::skew},
    {"skew_per_deg", &LandingParams::skew_per_deg},
    {"max_skew", &LandingParams::max_skew},
    {"peak_drop", &LandingParams::peak_drop},
    {"max_velocity_deg_s", &LandingParams::max_velocity_deg_s},
    {"main_sequence_ms", &LandingParams::main_sequence_ms},
    {"main_sequence_ms_per_deg", &LandingParams::main_sequence_ms_per_deg},
    {"main_sequence_vmax_deg_s", &LandingParams::main_sequence_vmax_deg_s},
    {"main_sequence_c_deg", &LandingParams::main_sequence_c_deg},
    {"duration_slack", &LandingParams::duration_slack},
};

}  // namespace

void set_landing_parameter(LandingParams& params, const std::string& name, double value) {
  for (const auto& [field, member] : kLandingFields)
    if (name == field) {
      if (!std::isfinite(value)) fail("{}: must be a finite number, got {}", name, value);
      params.*member = value;
      return;
    }
  std::string known;
  for (const auto& [field, member] : kLandingFields) known += (known.empty() ? "" : ", ") + std::string(field);
  fail("{}: no parameter of the landing predictor (known: {})", name, known);
}

std::vector<std::pair<std::string, double>> landing_parameters(const LandingParams& params) {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& [field, member] : kLandingFields) out.emplace_back(field, params.*member);
  return out;
}

LandingParams parse_landing_params(const std::string& text, LandingParams base) {
  size_t begin = text.find_first_not_of(" \t") == std::string::npos ? text.size() + 1 : 0;  // (nothing given: the base)
  std::vector<std::string> given;  // (a name twice is a slip, not a choice of the last)
  while (begin <= text.size()) {
    const size_t end = std::min(text.find(',', begin), text.size());
    auto trimmed = [](std::string s) {  // (spaces around names and values are allowed)
      s.erase(0, s.find_first_not_of(" \t"));
      s.erase(s.find_last_not_of(" \t") + 1);
      return s;
    };
    const std::string part = trimmed(text.substr(begin, end - begin));
    const size_t eq = part.find('=');
    const std::string name = trimmed(part.substr(0, eq)), number = eq == std::string::npos ? "" : trimmed(part.substr(eq + 1));
    if (name.empty() || number.empty()) fail("'{}': expected NAME=VALUE (as onset_deg_s=60)", part);
    double value = 0;
    try {
      size_t used = 0;
      value = std::stod(number, &used);
      if (used != number.size()) throw std::invalid_argument(number);
    } catch (const std::exception&) {
      fail("{}: '{}' is no number", name, number);
    }
    if (std::find(given.begin(), given.end(), name) != given.end()) fail("{}: given twice", name);
    given.push_back(name);
    set_landing_parameter(base, name, value);
    begin = end + 1;
  }
  validate(base);
  return base;
}

LandingPredictor::LandingPredictor(const LandingParams& params, bool keep_saccades) : params_(params), keep_saccades_(keep_saccades) {
  validate(params);
}

void LandingPredictor::reset() { *this = LandingPredictor(params_, keep_saccades_); }

void LandingPredictor::abandon() {
  state_.in_flight = false;
  state_.past_peak = false;
  rise_.clear();
  predictions_.clear();
  prediction_t_.clear();
}

void LandingPredictor::start(double t_s, glm::dvec2 from) {
  state_ = LandingState{};
  state_.in_flight = true;
  state_.onset_s = t_s;
  state_.onset_deg = from;
  state_.landing_deg = from;
  current_ = PredictedSaccade{};
  current_.onset_s = t_s;
  rise_.assign(1, Profile{});  // the rise starts at rest where the flight starts
  predictions_.clear();
  prediction_t_.clear();
  slow_since_ = NAN;
}

void LandingPredictor::predict(double t_s, glm::dvec2 deg, double velocity) {
  LandingState& s = state_;
  const glm::dvec2 travelled = deg - s.onset_deg;
  const double distance = glm::length(travelled);
  if (!s.past_peak) {
    if (velocity >= s.peak_velocity_deg_s) {
      s.peak_velocity_deg_s = velocity;
      rise_.push_back({t_s - s.onset_s, distance, velocity});
      slow_since_ = NAN;
    } else if (velocity < params_.peak_drop * s.peak_velocity_deg_s) {
      // Passed once the velocity has stayed below the drop for a velocity baseline (noise at the
      // start of a flight makes single dips)
      if (std::isnan(slow_since_)) slow_since_ = t_s;
      if (t_s - slow_since_ + sample_period_ >= kVelocityBaselineS - 1e-9) s.past_peak = true;
    } else {
      slow_since_ = NAN;
    }
  }
  // The rest of the flight mirrors the rise from the current velocity, stretched by the skew; while
  // the velocity still rises, as if it were the peak
  double rise_distance = distance, rise_time = t_s - s.onset_s;
  if (velocity < s.peak_velocity_deg_s) {
    const auto it = std::lower_bound(rise_.begin(), rise_.end(), velocity, [](const Profile& p, double v) { return p.velocity < v; });
    if (it == rise_.begin()) {
      rise_distance = rise_.empty() ? 0 : rise_.front().distance;
      rise_time = rise_.empty() ? 0 : rise_.front().t;
    } else if (it == rise_.end()) {
      rise_distance = rise_.back().distance;
      rise_time = rise_.back().t;
    } else {
      const Profile& a = *(it - 1);
      const Profile& b = *it;
      const double f = b.velocity > a.velocity ? (velocity - a.velocity) / (b.velocity - a.velocity) : 0;
      rise_distance = a.distance + f * (b.distance - a.distance);
      rise_time = a.t + f * (b.t - a.t);
    }
  }
  const double skew = std::min(params_.max_skew, params_.skew + params_.skew_per_deg * (distance + rise_distance));
  const double amplitude = distance + skew * rise_distance;
  const double landing_s = t_s + skew * rise_time;
  const glm::dvec2 dir = distance > 0 ? travelled / distance : glm::dvec2(0);
  s.amplitude_deg = amplitude;
  s.landing_deg = s.onset_deg + amplitude * dir;
  s.landing_s = landing_s;
  if (s.past_peak && std::isnan(current_.first_landing_deg.x)) {
    current_.first_prediction_s = t_s;
    current_.first_landing_deg = s.landing_deg;
    current_.first_landing_time_s = s.landing_s;
  }
  predictions_.push_back(s.landing_deg);
  prediction_t_.push_back(t_s);
}

void LandingPredictor::land(double t_s, glm::dvec2 deg) {
  LandingState& s = state_;
  const double amplitude = glm::length(deg - s.onset_deg);
  s.in_flight = false;
  s.landing_deg = deg;
  s.landing_s = t_s;
  s.amplitude_deg = amplitude;
  if (amplitude >= params_.min_flight_deg && s.past_peak && keep_saccades_) {
    current_.landing_s = t_s;
    current_.landing_deg = deg;
    current_.amplitude_deg = amplitude;
    // settled: the earliest prediction from which every later one was within 1° of the landing
    double settled = NAN;
    for (size_t k = predictions_.size(); k-- > 0;) {
      if (glm::length(predictions_[k] - deg) > 1.0) break;
      settled = prediction_t_[k];
    }
    current_.settled_s = settled;
    current_.prediction_s = prediction_t_;
    current_.prediction_deg = predictions_;
    done_.push_back(current_);
  }
  s.past_peak = false;
  rise_.clear();
  predictions_.clear();
  prediction_t_.clear();
}

void LandingPredictor::push(double t_s, glm::dvec2 deg, bool valid) {
  valid = valid && std::isfinite(deg.x) && std::isfinite(deg.y) && std::isfinite(t_s);
  if (!valid) {
    if (state_.in_flight) abandon();
    history_.clear();
    fast_run_ = 0;
    return;
  }
  if (!history_.empty() && t_s <= history_.back().t) return;  // out of order or repeated: ignored
  history_.push_back({t_s, deg});
  // The velocity over the last ≥ 4 ms (or one interval)
  while (history_.size() > 2 && t_s - history_[1].t >= kVelocityBaselineS) history_.erase(history_.begin());
  if (history_.size() < 2) return;
  const Sample& from = history_.front();
  const double dt = t_s - from.t;
  sample_period_ = t_s - history_[history_.size() - 2].t;
  const double velocity = glm::length(deg - from.deg) / dt;
  if (!(velocity <= params_.max_velocity_deg_s)) return;
  if (!state_.in_flight) {
    fast_run_ = velocity > params_.onset_deg_s ? fast_run_ + 1 : 0;
    if (fast_run_ == 1) {
      onset_candidate_ = from;
    } else if (fast_run_ >= 2) {
      start(onset_candidate_.t, onset_candidate_.deg);
      current_.detected_s = t_s;
      fast_run_ = 0;
      predict(t_s, 0.5 * (deg + from.deg), velocity);
    }
    return;
  }
  const double flight_ms = (t_s - state_.onset_s) * 1000;
  const double vmax = params_.main_sequence_vmax_deg_s;
  const double peak_amplitude = -params_.main_sequence_c_deg * std::log(1 - std::min(state_.peak_velocity_deg_s, 0.95 * vmax) / vmax);
  const double limit_ms = params_.duration_slack * (params_.main_sequence_ms + params_.main_sequence_ms_per_deg * peak_amplitude);
  if (flight_ms > limit_ms) {
    abandon();  // no deceleration where a saccade would have one: a pursuit or drift
    return;
  }
  if (state_.past_peak && velocity < params_.offset_deg_s) {
    land(t_s, deg);
    return;
  }
  // The velocity stands for the baseline's middle: so does the position the profile is mirrored from
  predict(t_s, 0.5 * (deg + from.deg), velocity);
}

glm::dvec2 PredictedSaccade::prediction_at(double t_s) const {
  const auto it = std::upper_bound(prediction_s.begin(), prediction_s.end(), t_s);
  if (it == prediction_s.begin()) return glm::dvec2(NAN);
  return prediction_deg[static_cast<size_t>(it - prediction_s.begin()) - 1];
}

std::vector<LandingReport> evaluate_landings(const Recording& recording, const GazeGeometry& geometry, const EventDetection& detection,
                                             const LandingParams& params) {
  std::vector<LandingReport> out;
  if (recording.samples.empty()) return out;
  const double t0 = recording.samples.front().t_s;
  std::vector<double> t;
  std::vector<glm::dvec2> deg;
  for (const GazeSample& s : recording.samples) {
    t.push_back(s.t_s - t0);
    const glm::dvec2 a = GazeGeometry::angles_deg(geometry.direction(s));
    deg.push_back(s.valid ? glm::dvec2(a.x, -a.y) : glm::dvec2(NAN));  // y up, as the detection's positions
  }
  const std::vector<PredictedSaccade> flights = predict_landings(t, deg, params);
  for (size_t k = 0; k < detection.events.size(); ++k) {
    const DetectedEvent& e = detection.events[k];
    if (e.label != EventLabel::saccade) continue;
    LandingReport r;
    r.event = k;
    r.onset_s = t[e.first];
    r.landing_s = t[e.last];
    r.amplitude_deg = e.amplitude_deg;
    r.landing_deg = e.end_deg;
    for (const PredictedSaccade& f : flights) {
      if (f.onset_s < r.onset_s - 0.020 || f.onset_s > r.landing_s) continue;
      r.predicted = true;
      r.first_deg = f.first_landing_deg;
      r.first_error_deg = glm::length(f.first_landing_deg - r.landing_deg);
      r.two_thirds_deg = f.prediction_at(r.onset_s + (r.landing_s - r.onset_s) * 2 / 3);
      r.two_thirds_error_deg = glm::length(r.two_thirds_deg - r.landing_deg);
      r.gained_ms = std::isnan(f.settled_s) ? NAN : 1000 * (r.landing_s - f.settled_s);
      break;
    }
    out.push_back(r);
  }
  return out;
}

std::string landings_tsv(const std::vector<LandingReport>& reports) {
  auto num = [](double v) { return std::isfinite(v) ? fmt::format("{:.4f}", v) : std::string("n/a"); };
  std::string text =
      "onset\tlanding\tamplitude_deg\tend_x_deg\tend_y_deg\tpredicted_x_deg\tpredicted_y_deg\terror_deg\ttwo_thirds_x_deg\t"
      "two_thirds_y_deg\ttwo_thirds_error_deg\tgained_ms\n";
  for (const LandingReport& r : reports)
    text += fmt::format("{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\n", num(r.onset_s), num(r.landing_s), num(r.amplitude_deg),
                        num(r.landing_deg.x), num(r.landing_deg.y), num(r.first_deg.x), num(r.first_deg.y), num(r.first_error_deg),
                        num(r.two_thirds_deg.x), num(r.two_thirds_deg.y), num(r.two_thirds_error_deg), num(r.gained_ms));
  return text;
}

std::vector<PredictedSaccade> predict_landings(const std::vector<double>& t_s, const std::vector<glm::dvec2>& deg,
                                               const LandingParams& params) {
  if (t_s.size() != deg.size()) fail("predict_landings: {} times for {} positions", t_s.size(), deg.size());
  LandingPredictor predictor(params, true);
  for (size_t i = 0; i < t_s.size(); ++i) predictor.push(t_s[i], deg[i]);
  return predictor.saccades();
}

}  // namespace foveal
