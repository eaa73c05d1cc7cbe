// foveal/gaze/fixation.cpp — I-VT, I-DT, agreement, the causal tracker and the screen mapping.
#include "foveal/gaze/fixation.h"

#include "foveal/util/error.h"
#include "foveal/util/parse.h"

#include <algorithm>
#include <cmath>

namespace foveal {

namespace {
// Time windows are decided with a tolerance of 1 µs (a tenth of the shortest sampling interval of
// any tracker), so that a sample exactly at a window's edge is inside it whatever the rounding of
// the absolute timestamps: the same recording with its clock shifted gives the same fixations.
constexpr double kTimeTolerance_s = 1e-6;
bool within(double dt, double limit) { return dt <= limit + kTimeTolerance_s; }   // dt ≤ limit
bool reaches(double dt, double limit) { return dt >= limit - kTimeTolerance_s; }  // dt ≥ limit
bool inside(double dt, double limit) { return dt < limit - kTimeTolerance_s; }    // dt < limit: the edge is outside
}  // namespace

// ---------------------------------------------------------------------------------------------
// Geometry

GazeGeometry::GazeGeometry(const Display& display, glm::ivec2 screen_px)
    : screen_(screen_px), cm_per_px_(display.width_cm / screen_px.x, display.height_cm / screen_px.y), distance_cm_(display.distance_cm) {
  if (screen_px.x < 1 || screen_px.y < 1) fail("gaze screen must be at least 1x1 pixels");
}

glm::dvec2 GazeGeometry::angles_deg(glm::dvec3 d) { return glm::degrees(glm::dvec2(std::atan2(d.x, d.z), std::atan2(d.y, d.z))); }

double GazeGeometry::pixels_per_degree() const {
  return screen_.x / glm::degrees(2 * std::atan(0.5 * screen_.x * cm_per_px_.x / distance_cm_));
}

double angle_between_deg(glm::dvec3 a, glm::dvec3 b) {
  // atan2 of |a×b| and a·b keeps precision where acos would not
  return glm::degrees(std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)));
}

const char* to_string(FixationMethod m) {
  switch (m) {
    case FixationMethod::mean:
      return "mean";
    case FixationMethod::ivt:
      return "ivt";
    case FixationMethod::idt:
      return "idt";
    case FixationMethod::ivvt:
      return "ivvt";
  }
  return "?";
}

FixationMethod parse_fixation_method(const std::string& name) {
  for (FixationMethod m : {FixationMethod::mean, FixationMethod::ivt, FixationMethod::idt, FixationMethod::ivvt})
    if (name == to_string(m)) return m;
  fail("fixation: unknown filter '{}' (expected ivvt, mean, ivt or idt)", name);
}

void validate(const FixationParams& p) {
  require_positive(p.velocity_threshold_deg_s, "velocity_threshold_deg_s");
  require_positive(p.velocity_window_s, "velocity_window_s");
  require_non_negative(p.gap_fill_s, "gap_fill_s");
  require_non_negative(p.merge_gap_s, "merge_gap_s");
  require_non_negative(p.merge_angle_deg, "merge_angle_deg");
  require_non_negative(p.min_fixation_s, "min_fixation_s");
  if (p.median_window < 1 || p.median_window > 99 || p.median_window % 2 == 0)
    fail("median_window: must be an odd number of samples from 1 (off) to 99, got {}", p.median_window);
  require_positive(p.dispersion_deg, "dispersion_deg");
  require_non_negative(p.min_duration_s, "min_duration_s");
  validate(p.pursuit);
  if (!(p.pursuit.velocity_deg_s < p.velocity_threshold_deg_s))
    fail("pursuit_velocity_deg_s: must be below the saccade threshold velocity_threshold_deg_s ({} deg/s), got {}",
         p.velocity_threshold_deg_s, p.pursuit.velocity_deg_s);
}

void validate(const PursuitParams& p) {
  require_positive(p.velocity_deg_s, "pursuit_velocity_deg_s");
  require_positive(p.window_s, "pursuit_window_s");
  require_non_negative(p.min_s, "pursuit_min_s");
  require_non_negative(p.travel_fraction, "pursuit_travel_fraction");
}

// ---------------------------------------------------------------------------------------------
// Preparation shared by the offline filters: directions, gap fill, runs

namespace {

struct Prepared {
  std::vector<glm::dvec3> dir;
  std::vector<glm::dvec2> angles;  // degrees
  std::vector<bool> usable;        // valid, or inside a filled gap
  std::vector<int> run;            // samples of one run have no unusable sample or long gap between them
};

Prepared prepare(const Recording& r, const GazeGeometry& g, const FixationParams& p) {
  const auto& s = r.samples;
  const size_t n = s.size();
  Prepared out;
  out.dir.assign(n, glm::dvec3(0, 0, 1));
  out.usable.assign(n, false);
  for (size_t i = 0; i < n; ++i)
    if (s[i].valid) {
      out.dir[i] = g.direction(s[i]);
      out.usable[i] = true;
    }
  // Gap fill: invalid stretches between valid samples at most gap_fill_s apart are interpolated
  size_t last_valid = n;
  for (size_t i = 0; i < n; ++i) {
    if (!s[i].valid) continue;
    if (last_valid != n && i > last_valid + 1 && within(s[i].t_s - s[last_valid].t_s, p.gap_fill_s)) {
      const double t0 = s[last_valid].t_s, span = s[i].t_s - t0;
      for (size_t k = last_valid + 1; k < i; ++k) {
        const double w = span > 0 ? (s[k].t_s - t0) / span : 0.5;
        out.dir[k] = glm::normalize(glm::mix(out.dir[last_valid], out.dir[i], w));
        out.usable[k] = true;
      }
    }
    last_valid = i;
  }
  out.angles.resize(n);
  for (size_t i = 0; i < n; ++i) out.angles[i] = GazeGeometry::angles_deg(out.dir[i]);
  // Runs: broken by unusable samples and by time gaps longer than the gap fill (block breaks)
  out.run.assign(n, -1);
  int run = -1;
  for (size_t i = 0; i < n; ++i) {
    if (!out.usable[i]) continue;
    const bool continues = i > 0 && out.usable[i - 1] && within(s[i].t_s - s[i - 1].t_s, p.gap_fill_s);
    if (!continues) ++run;
    out.run[i] = run;
  }
  // Noise reduction (Tobii's optional moving median): each angle → the median of its window in the run
  if (p.median_window > 1) {
    const int half = p.median_window / 2;
    std::vector<glm::dvec2> smoothed = out.angles;
    std::vector<double> xs, ys;
    for (size_t i = 0; i < n; ++i) {
      if (out.run[i] < 0) continue;
      xs.clear();
      ys.clear();
      for (size_t k = i >= static_cast<size_t>(half) ? i - half : 0; k < n && k <= i + half; ++k)
        if (out.run[k] == out.run[i]) {
          xs.push_back(out.angles[k].x);
          ys.push_back(out.angles[k].y);
        }
      std::nth_element(xs.begin(), xs.begin() + xs.size() / 2, xs.end());
      std::nth_element(ys.begin(), ys.begin() + ys.size() / 2, ys.end());
      smoothed[i] = {xs[xs.size() / 2], ys[ys.size() / 2]};
      const glm::dvec2 t = glm::tan(glm::radians(smoothed[i]));
      out.dir[i] = glm::normalize(glm::dvec3(t.x, t.y, 1.0));
    }
    out.angles = smoothed;
  }
  return out;
}

// Fixation centre: mean of the valid samples in [first, last] (of the filled ones if none is valid).
glm::dvec2 centre(const Recording& r, size_t first, size_t last) {
  glm::dvec2 sum{0};
  size_t count = 0;
  for (size_t i = first; i <= last; ++i)
    if (r.samples[i].valid) {
      sum += r.samples[i].px;
      ++count;
    }
  return count ? sum / static_cast<double>(count) : glm::dvec2(NAN);
}

Fixation make_fixation(const Recording& r, size_t first, size_t last) {
  Fixation f;
  f.first = first;
  f.last = last;
  f.start_s = r.samples[first].t_s;
  f.end_s = r.samples[last].t_s;
  f.px = centre(r, first, last);
  return f;
}

FixationResult with_labels(std::vector<Fixation> fixations, size_t n) {
  FixationResult out;
  out.label.assign(n, -1);
  for (const Fixation& f : fixations) {
    for (size_t i = f.first; i <= f.last; ++i) out.label[i] = static_cast<int>(out.fixations.size());
    out.fixations.push_back(f);
  }
  return out;
}

}  // namespace

FixationResult detect_ivt(const Recording& r, const GazeGeometry& g, const FixationParams& p) {
  validate(p);
  const auto& s = r.samples;
  const size_t n = s.size();
  const Prepared prep = prepare(r, g, p);
  // Velocity over the window centred on each sample, within its run
  std::vector<bool> slow(n, false);
  const double half = 0.5 * p.velocity_window_s;
  size_t lo = 0, hi = 0;
  for (size_t i = 0; i < n; ++i) {
    if (prep.run[i] < 0) continue;
    if (lo > i) lo = i;
    while (lo < i && (prep.run[lo] != prep.run[i] || !inside(s[i].t_s - s[lo].t_s, half))) ++lo;
    hi = std::max(hi, i);
    while (hi + 1 < n && prep.run[hi + 1] == prep.run[i] && inside(s[hi + 1].t_s - s[i].t_s, half)) ++hi;
    size_t a = lo, b = hi;
    if (a == b) {  // the window holds this sample only: use its neighbours in the run
      if (i + 1 < n && prep.run[i + 1] == prep.run[i])
        b = i + 1;
      else if (i > 0 && prep.run[i - 1] == prep.run[i])
        a = i - 1;
      else
        continue;
    }
    const double dt = s[b].t_s - s[a].t_s;
    if (dt <= 0) continue;
    slow[i] = angle_between_deg(prep.dir[a], prep.dir[b]) / dt < p.velocity_threshold_deg_s;
  }
  // Runs of slow samples become fixations
  std::vector<Fixation> fixations;
  for (size_t i = 0; i < n;) {
    if (!slow[i]) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j + 1 < n && slow[j + 1] && prep.run[j + 1] == prep.run[i]) ++j;
    fixations.push_back(make_fixation(r, i, j));
    i = j + 1;
  }
  // Merge neighbours close in time and angle
  std::vector<Fixation> merged;
  for (const Fixation& f : fixations) {
    if (!merged.empty()) {
      Fixation& m = merged.back();
      const bool close_in_time = within(f.start_s - m.end_s, p.merge_gap_s);
      const bool close_in_angle =
          std::isfinite(m.px.x) && std::isfinite(f.px.x) && angle_between_deg(g.direction(m.px), g.direction(f.px)) <= p.merge_angle_deg;
      if (close_in_time && close_in_angle) {
        m = make_fixation(r, m.first, f.last);
        continue;
      }
    }
    merged.push_back(f);
  }
  // Discard short ones
  std::erase_if(merged, [&](const Fixation& f) { return !reaches(f.duration_s(), p.min_fixation_s) || !std::isfinite(f.px.x); });
  return with_labels(std::move(merged), n);
}

FixationResult detect_idt(const Recording& r, const GazeGeometry& g, const FixationParams& p) {
  validate(p);
  const auto& s = r.samples;
  const size_t n = s.size();
  const Prepared prep = prepare(r, g, p);
  std::vector<Fixation> fixations;
  size_t i = 0;
  while (i < n) {
    if (prep.run[i] < 0) {
      ++i;
      continue;
    }
    // The smallest window from i that spans the minimum duration
    size_t j = i;
    while (j + 1 < n && prep.run[j + 1] == prep.run[i] && !reaches(s[j].t_s - s[i].t_s, p.min_duration_s)) ++j;
    if (!reaches(s[j].t_s - s[i].t_s, p.min_duration_s)) {  // the run ends first
      i = j + 1;
      continue;
    }
    glm::dvec2 lo = prep.angles[i], hi = prep.angles[i];
    for (size_t k = i + 1; k <= j; ++k) {
      lo = glm::min(lo, prep.angles[k]);
      hi = glm::max(hi, prep.angles[k]);
    }
    auto dispersion = [](glm::dvec2 a, glm::dvec2 b) { return (b.x - a.x) + (b.y - a.y); };
    if (dispersion(lo, hi) > p.dispersion_deg) {
      ++i;
      continue;
    }
    // Grow the window while the dispersion stays within the limit
    while (j + 1 < n && prep.run[j + 1] == prep.run[i]) {
      const glm::dvec2 lo2 = glm::min(lo, prep.angles[j + 1]), hi2 = glm::max(hi, prep.angles[j + 1]);
      if (dispersion(lo2, hi2) > p.dispersion_deg) break;
      lo = lo2;
      hi = hi2;
      ++j;
    }
    Fixation f = make_fixation(r, i, j);
    if (std::isfinite(f.px.x)) fixations.push_back(f);
    i = j + 1;
  }
  return with_labels(std::move(fixations), n);
}

std::vector<bool> fixation_mask(const FixationResult& result) {
  std::vector<bool> mask(result.label.size());
  for (size_t i = 0; i < mask.size(); ++i) mask[i] = result.label[i] >= 0;
  return mask;
}

Agreement agreement_with_events(const Recording& r, const std::vector<bool>& is_fixation, const std::vector<GazeEvent>& events) {
  if (is_fixation.size() != r.samples.size()) fail("agreement: {} labels for {} samples", is_fixation.size(), r.samples.size());
  std::vector<GazeEvent> sorted = events;
  std::sort(sorted.begin(), sorted.end(), [](const GazeEvent& a, const GazeEvent& b) { return a.start_s < b.start_s; });
  // Sweep: an event may overlap the next; track the furthest end seen among started events
  size_t next = 0, n_valid = 0, both = 0, filter_only = 0, reference_only = 0;
  double open_until = -INFINITY;
  for (size_t i = 0; i < r.samples.size(); ++i) {
    const double t = r.samples[i].t_s;
    while (next < sorted.size() && sorted[next].start_s <= t) open_until = std::max(open_until, sorted[next++].end_s);
    if (!r.samples[i].valid) continue;
    const bool reference = t <= open_until, filter = is_fixation[i];
    ++n_valid;
    both += reference && filter;
    filter_only += filter && !reference;
    reference_only += reference && !filter;
  }
  Agreement a;
  a.samples = n_valid;
  if (n_valid == 0) return a;
  const double n = static_cast<double>(n_valid);
  const double neither = n - both - filter_only - reference_only;
  a.agreement = (both + neither) / n;
  a.filter_fraction = (both + filter_only) / n;
  a.reference_fraction = (both + reference_only) / n;
  const double expected = a.filter_fraction * a.reference_fraction + (1 - a.filter_fraction) * (1 - a.reference_fraction);
  a.kappa = expected < 1 ? (a.agreement - expected) / (1 - expected) : (a.agreement == 1 ? 1.0 : 0.0);
  return a;
}

// ---------------------------------------------------------------------------------------------
// The causal tracker

FixationTracker::FixationTracker(FixationMethod method, const FixationParams& params, const GazeGeometry& geometry)
    : method_(method), params_(params), geometry_(geometry) {
  validate(params_);
}

void FixationTracker::reset_candidate() {
  window_.clear();
  recent_.clear();
  line_.clear();
  in_pursuit_ = false;
  pursuit_start_t_ = NAN;
  candidate_sum_ = glm::dvec2(0);
  candidate_count_ = 0;
  in_fixation_ = false;
}

void FixationTracker::push(const GazeSample& s) {
  if (!s.valid) {
    // A gap longer than the gap fill ends any candidate; the output is held either way
    if (!within(s.t_s - last_valid_t_, params_.gap_fill_s) && method_ != FixationMethod::mean) reset_candidate();
    if (method_ == FixationMethod::mean) in_fixation_ = false;
    return;
  }
  if (!within(s.t_s - last_valid_t_, params_.gap_fill_s) && method_ != FixationMethod::mean) reset_candidate();
  last_valid_t_ = s.t_s;
  const glm::dvec3 dir = geometry_.direction(s);
  Entry e{s.t_s, dir, s.px, GazeGeometry::angles_deg(dir)};
  if (params_.median_window > 1) {  // causal moving median over the last samples
    recent_.push_back(e);
    if (recent_.size() > static_cast<size_t>(params_.median_window)) recent_.pop_front();
    auto median = [&](auto get) {
      std::vector<double> v;
      for (const Entry& r : recent_) v.push_back(get(r));
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      return v[v.size() / 2];
    };
    e.angles = {median([](const Entry& r) { return r.angles.x; }), median([](const Entry& r) { return r.angles.y; })};
    e.px = {median([](const Entry& r) { return r.px.x; }), median([](const Entry& r) { return r.px.y; })};
    const glm::dvec2 t = glm::tan(glm::radians(e.angles));
    e.dir = glm::normalize(glm::dvec3(t.x, t.y, 1.0));
  }
  switch (method_) {
    case FixationMethod::mean:
      frame_sum_ += s.px;
      ++frame_count_;
      in_fixation_ = true;
      break;
    case FixationMethod::ivt:
      push_ivt(e);
      break;
    case FixationMethod::idt:
      push_idt(e);
      break;
    case FixationMethod::ivvt:
      push_ivvt(e);
      break;
  }
}

std::optional<double> FixationTracker::window_velocity(const Entry& e) {
  // Velocity from the oldest sample within the window behind this one
  window_.push_back(e);
  while (window_.size() > 2 && reaches(e.t - window_[1].t, params_.velocity_window_s)) window_.pop_front();
  if (window_.size() < 2) return std::nullopt;
  const Entry& a = window_.front();
  const double dt = e.t - a.t;
  if (dt <= 0) return std::nullopt;
  return angle_between_deg(a.dir, e.dir) / dt;
}

void FixationTracker::add_to_fixation(const Entry& e) {
  if (candidate_count_ == 0) candidate_start_ = e.t;
  candidate_sum_ += e.px;
  ++candidate_count_;
  if (reaches(e.t - candidate_start_, params_.min_fixation_s)) {
    in_fixation_ = true;
    output_ = candidate_sum_ / static_cast<double>(candidate_count_);
  }
}

void FixationTracker::end_fixation() {
  candidate_sum_ = glm::dvec2(0);
  candidate_count_ = 0;
  in_fixation_ = false;
}

void FixationTracker::push_ivt(const Entry& e) {
  const std::optional<double> velocity = window_velocity(e);
  if (!velocity) return;
  if (*velocity >= params_.velocity_threshold_deg_s) {  // saccade: hold the last fixation
    end_fixation();
    return;
  }
  add_to_fixation(e);
}

void FixationTracker::push_idt(const Entry& e) {
  auto dispersion = [](glm::dvec2 lo, glm::dvec2 hi) { return (hi.x - lo.x) + (hi.y - lo.y); };
  if (in_fixation_) {
    const glm::dvec2 lo = glm::min(lo_, e.angles), hi = glm::max(hi_, e.angles);
    if (dispersion(lo, hi) <= params_.dispersion_deg) {  // the fixation goes on
      lo_ = lo;
      hi_ = hi;
      candidate_sum_ += e.px;
      ++candidate_count_;
      output_ = candidate_sum_ / static_cast<double>(candidate_count_);
      return;
    }
    reset_candidate();  // it ended; this sample starts the next window
  }
  window_.push_back(e);
  // Drop the oldest samples until the window is within the limit
  for (;;) {
    glm::dvec2 lo = window_.front().angles, hi = lo;
    for (const Entry& w : window_) {
      lo = glm::min(lo, w.angles);
      hi = glm::max(hi, w.angles);
    }
    if (dispersion(lo, hi) <= params_.dispersion_deg) {
      lo_ = lo;
      hi_ = hi;
      break;
    }
    window_.pop_front();
  }
  if (reaches(window_.back().t - window_.front().t, params_.min_duration_s)) {
    in_fixation_ = true;
    candidate_sum_ = glm::dvec2(0);
    for (const Entry& w : window_) candidate_sum_ += w.px;
    candidate_count_ = window_.size();
    window_.clear();
    output_ = candidate_sum_ / static_cast<double>(candidate_count_);
  }
}

void FixationTracker::push_ivvt(const Entry& e) {
  // The pursuit window: a least-squares line through the angles (and the pixels) over time
  line_.push_back(e);
  // (at most 512 samples: 40 ms at 12.8 kHz; a clock in the wrong unit must not make each sample's
  // fit cost the whole recording)
  while (line_.size() > 2 && (!within(e.t - line_.front().t, params_.pursuit.window_s) || line_.size() > 512)) line_.pop_front();
  const std::optional<double> velocity = window_velocity(e);
  if (!velocity) return;
  if (*velocity >= params_.velocity_threshold_deg_s) {  // saccade: hold the last fixation or pursuit position
    end_fixation();
    in_pursuit_ = false;
    pursuit_start_t_ = NAN;
    return;
  }
  double st = 0, stt = 0;
  glm::dvec2 sa(0), sta(0), sp(0), stp(0);
  const double t0 = line_.front().t;
  for (const Entry& x : line_) {
    const double t = x.t - t0;
    st += t;
    stt += t * t;
    sa += x.angles;
    sta += t * x.angles;
    sp += x.px;
    stp += t * x.px;
  }
  const double n = static_cast<double>(line_.size()), denom = n * stt - st * st;
  // The slope only once the window is (nearly: irregular clocks) full; a few samples' slope is noise
  const bool full = line_.size() >= 3 && reaches(e.t - t0, 0.75 * params_.pursuit.window_s) && denom > 0;
  const double speed = full ? glm::length((n * sta - st * sa) / denom) : 0;  // deg/s
  if (!(speed > params_.pursuit.velocity_deg_s)) {
    // Slow: a fixation sample; a pursuit ends here and a fixation starts anew
    if (in_pursuit_) {
      in_pursuit_ = false;
      end_fixation();
    }
    pursuit_start_t_ = NAN;
    add_to_fixation(e);
    return;
  }
  // Pursuit-fast: not a fixation sample. The run becomes pursuit once it has lasted the minimum
  // and covered at least half the distance its speeds imply (noise's slopes do not add up)
  if (std::isnan(pursuit_start_t_)) {
    pursuit_start_t_ = e.t;
    pursuit_start_dir_ = e.dir;
    pursuit_distance_ = 0;
  } else {
    pursuit_distance_ += speed * (e.t - pursuit_last_t_);
  }
  pursuit_last_t_ = e.t;
  if (!in_pursuit_ && reaches(e.t - pursuit_start_t_, params_.pursuit.min_s) &&
      angle_between_deg(pursuit_start_dir_, e.dir) >= 0.5 * pursuit_distance_) {
    in_pursuit_ = true;
    end_fixation();
  }
  if (in_pursuit_) {  // the line's position at the latest sample
    const glm::dvec2 slope_px = (n * stp - st * sp) / denom;
    output_ = (sp - slope_px * st) / n + slope_px * (e.t - t0);
  }
}

std::optional<glm::dvec2> FixationTracker::frame_gaze() {
  if (method_ == FixationMethod::mean && frame_count_ > 0) {
    output_ = frame_sum_ / static_cast<double>(frame_count_);
    frame_sum_ = glm::dvec2(0);
    frame_count_ = 0;
  }
  return output_;
}

// ---------------------------------------------------------------------------------------------
// Screen → render

glm::dvec2 ScreenMapping::to_render(glm::dvec2 p) const {
  return (p - glm::dvec2(rect.x, rect.y)) / glm::dvec2(rect.z, rect.w) * glm::dvec2(render_px);
}

ScreenMapping make_screen_mapping(glm::ivec2 screen_px, glm::ivec2 render_px, const std::string& rect) {
  ScreenMapping m;
  m.screen_px = screen_px;
  m.render_px = render_px;
  m.rect = {0, 0, screen_px.x, screen_px.y};
  if (!rect.empty()) {
    const auto v = parse_numbers("stimulus", rect, 4);
    if (!(v[2] > 0 && v[3] > 0)) fail("stimulus: width and height must be positive, got '{}'", rect);
    m.rect = {v[0], v[1], v[2], v[3]};
  }
  return m;
}

}  // namespace foveal
