// foveal/gaze/detect.cpp — the event detectors of detect.h.
#include "foveal/gaze/detect.h"

#include "foveal/util/error.h"
#include "foveal/util/parse.h"
#include "foveal/util/units.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>

namespace foveal {

const char* to_string(EventMethod m) {
  switch (m) {
    case EventMethod::ivt:
      return "ivt";
    case EventMethod::idt:
      return "idt";
    case EventMethod::ek:
      return "ek";
    case EventMethod::nh:
      return "nh";
    case EventMethod::nhp:
      return "nhp";
    case EventMethod::nhr:
      return "nhr";
    case EventMethod::ivvt:
      return "ivvt";
  }
  return "?";
}

EventMethod parse_event_method(const std::string& name) {
  if (name == "auto") return kRecommendedEventMethod;
  for (EventMethod m :
       {EventMethod::ivt, EventMethod::idt, EventMethod::ivvt, EventMethod::ek, EventMethod::nh, EventMethod::nhp, EventMethod::nhr})
    if (name == to_string(m)) return m;
  fail("events: unknown detector '{}' (ivt, idt, ivvt, ek, nh, nhp, nhr or auto)", name);
}

// Errors name the parameter by its field (the command line names its own options: apps/).
void validate(const EventParams& p) {
  require_non_negative(p.blink_flank_s, "blink_flank_s");
  require_positive(p.max_blink_s, "max_blink_s");
  require_positive(p.pupil_deviation, "pupil_deviation");
  require_positive(p.filter_window_s, "filter_window_s");
  require_positive(p.initial_peak_deg_s, "initial_peak_deg_s");
  require_positive(p.max_velocity_deg_s, "max_velocity_deg_s");
  require_positive(p.max_acceleration_deg_s2, "max_acceleration_deg_s2");
  require_non_negative(p.min_saccade_s, "min_saccade_s");
  require_non_negative(p.min_fixation_s, "min_fixation_s");
  require_non_negative(p.pso_window_s, "pso_window_s");
  require_positive(p.local_noise_s, "local_noise_s");
  require_non_negative(p.detection_window_s, "detection_window_s");
  require_non_negative(p.lid_saccade_s, "lid_saccade_s");
  require_positive(p.ek_lambda, "ek_lambda");
  require_non_negative(p.ek_min_saccade_s, "ek_min_saccade_s");
  validate(p.pursuit);
  require_non_negative(p.max_dropout_s, "max_dropout_s");
  require_non_negative(p.robust_pso_window_s, "robust_pso_window_s");
  require_positive(p.robust_filter_window_s, "robust_filter_window_s");
  require_positive(p.threshold_window_s, "threshold_window_s");
  require_positive(p.robust_peak_k, "robust_peak_k");
  require_positive(p.robust_onset_k, "robust_onset_k");
  if (p.robust_onset_k > p.robust_peak_k) fail("robust_onset_k: {} is above robust_peak_k ({})", p.robust_onset_k, p.robust_peak_k);
  require_positive(p.min_peak_deg_s, "min_peak_deg_s");
  validate(p.slow_pursuit);
  require_positive(p.pursuit_keep, "pursuit_keep");
  require_non_negative(p.pursuit_edge_s, "pursuit_edge_s");
  require_non_negative(p.saccade_trough, "saccade_trough");
  if (p.saccade_trough > 1) fail("saccade_trough: {} is above 1", p.saccade_trough);
  if (p.pursuit_keep > 1) fail("pursuit_keep: {} is above 1", p.pursuit_keep);
  require_non_negative(p.settle_s, "settle_s");
  require_non_negative(p.context_s, "context_s");
  require_non_negative(p.context_relax, "context_relax");
  require_non_negative(p.context_min_fraction, "context_min_fraction");
  if (!(p.context_cos >= -1 && p.context_cos <= 1)) fail("context_cos: {} is not in [-1, 1]", p.context_cos);
}

std::pair<double, double> adaptive_velocity_thresholds(const std::vector<float>& v, double initial) {
  double peak = initial, mean = 0, sd = 0;
  for (int iteration = 0; iteration < 200; ++iteration) {
    double sum = 0, sum2 = 0;
    size_t count = 0;
    for (float x : v)
      if (x < peak) {  // NaN compares false: left out
        sum += x;
        sum2 += static_cast<double>(x) * x;
        ++count;
      }
    if (count < 2) break;
    mean = sum / count;
    sd = std::sqrt(std::max(0.0, sum2 / count - mean * mean));
    const double next = mean + 6 * sd;
    const bool converged = std::abs(next - peak) < 1;
    peak = next;
    if (converged) break;
  }
  return {peak, mean + 3 * sd};
}

namespace {

struct Signal {
  size_t n = 0;
  double dt = 0;
  std::vector<double> t;  // the samples' times, apart from the samples (the passes read them contiguously)
  std::vector<glm::dvec3> dir;
  std::vector<float> valid_pupils;           // the finite pupils of the samples the recording calls valid
  std::vector<uint8_t> valid;                // bytes, not std::vector<bool>: read at every sample by every pass
  std::vector<uint8_t> noise;                // nh: physiologically impossible velocity or acceleration (never free)
  std::vector<uint32_t> run_start, run_end;  // per sample: its run of contiguous valid samples [start, end)
};

Signal prepare(const Recording& r, const GazeGeometry& g, double max_fill_s = 0) {
  Signal s;
  s.n = r.samples.size();
  if (s.n >= std::numeric_limits<uint32_t>::max())
    fail("a recording of {} samples: at most {} can be labelled", s.n, std::numeric_limits<uint32_t>::max() - 1);
  s.t.resize(s.n);
  s.valid_pupils.reserve(s.n);
  s.dir.resize(s.n);
  s.valid.resize(s.n);
  s.noise.assign(s.n, 0);
  // One pass over the samples (72 bytes each); the passes below read the compact arrays
  for (size_t i = 0; i < s.n; ++i) {
    const GazeSample& sample = r.samples[i];
    s.t[i] = sample.t_s;
    s.valid[i] = sample.valid;
    s.dir[i] = sample.valid ? g.direction(sample) : glm::dvec3(0, 0, 1);
    if (sample.valid && std::isfinite(sample.pupil)) s.valid_pupils.push_back(sample.pupil);
  }
  // The sampling interval: the median of (at most 4096, evenly spread) intervals
  std::vector<double> intervals;
  intervals.reserve(4097);
  for (size_t i = 1 + s.n / 4096, stride = 1 + s.n / 4096; i < s.n; i += stride)
    if (s.t[i] > s.t[i - 1]) intervals.push_back(s.t[i] - s.t[i - 1]);
  if (intervals.empty()) {
    s.dt = 0.001;
  } else {
    auto mid = intervals.begin() + intervals.size() / 2;
    std::nth_element(intervals.begin(), mid, intervals.end());
    s.dt = *mid;
  }
  // Dropouts (nhr): losses no longer than max_fill_s between two valid samples, filled along the
  // great circle between them so that the velocity and the events run through them
  if (max_fill_s > 0)
    for (size_t i = 1; i + 1 < s.n; ++i) {
      if (s.valid[i] || !s.valid[i - 1]) continue;
      size_t j = i;
      while (j < s.n && !s.valid[j]) ++j;
      if (j < s.n && s.t[j] - s.t[i - 1] <= max_fill_s + 1.5 * s.dt) {
        const glm::dvec3 a = s.dir[i - 1], b = s.dir[j];
        for (size_t k = i; k < j; ++k) {
          const double u = double(k - i + 1) / double(j - i + 1);
          s.dir[k] = glm::normalize((1 - u) * a + u * b);
          s.valid[k] = 1;
        }
      }
      i = j;
    }
  s.run_start.assign(s.n, 0);
  s.run_end.assign(s.n, 0);
  for (size_t i = 0; i < s.n;) {
    if (!s.valid[i]) {
      s.run_start[i] = s.run_end[i] = static_cast<uint32_t>(i);
      ++i;
      continue;
    }
    size_t j = i + 1;
    const double gap = 1.5 * s.dt;
    while (j < s.n && s.valid[j] && s.t[j] - s.t[j - 1] < gap) ++j;
    for (size_t k = i; k < j; ++k) {
      s.run_start[k] = static_cast<uint32_t>(i);
      s.run_end[k] = static_cast<uint32_t>(j);
    }
    i = j;
  }
  return s;
}

// Least-squares fits over centred windows, by sums: O(1) per sample whatever the window.
//   The line's velocity per unit of Σ k·d for each half-width w ≤ h: kDeg / (Σ_{|k|≤w} k² · dt), and
//   the parabola's acceleration per unit of Σ (k² − m)·d (m = Σk²/(2h+1)), full windows only
// (made once per filter, not a division per sample).
struct LineScales {
  int h;
  std::vector<double> by_width;  // [1, h]
  double m = 0, acceleration = 0;
  LineScales(int h_, double dt) : h(h_), by_width(static_cast<size_t>(h_) + 1, 0.0) {
    for (int w = 1; w <= h; ++w)  // Σ k² over |k| ≤ w = w(w + 1)(2w + 1)/3, an exact integer
      by_width[static_cast<size_t>(w)] = kDeg / (double(w) * (w + 1) * (2 * w + 1) / 3 * dt);
    double s2 = 0, s4 = 0;
    for (int k = -h; k <= h; ++k) s2 += double(k) * k;
    m = s2 / (2 * h + 1);
    for (int k = -h; k <= h; ++k) s4 += (k * k - m) * (k * k - m);
    acceleration = 2 * kDeg / (s4 * dt * dt);
  }
};

// Prefix sums of one block of a run, per coordinate.
struct FitScratch {
  std::vector<double> p[9];  // Σ d, Σ k·d, Σ k²·d for x, y, z; [j]: over the block's first j samples
};

// One filter's output over the runs: the speed per sample (squared where `squared`: where it is only
// compared with thresholds, squares compared with squared thresholds decide the same, and a square
// root is the costliest step of a sample's fit), and, where `acceleration`, the squared
// acceleration at full windows (for the same reason).
struct FitOutput {
  const LineScales* scales = nullptr;
  float* velocity = nullptr;
  float* acceleration = nullptr;
  bool squared = false;
};

// Velocity (and acceleration) of every sample of the run [start, end), for each output: the
// least-squares line (parabola) over the largest centred window of half-width at most its h inside
// the run (a run's first and last sample: the one-sided difference; a run of one sample: left NaN).
// The sums, shared by the outputs, are taken afresh for each block of 512 centres, with k counted
// from the block's start, so that neither rounding builds up nor large k cancel: the velocities
// equal those of the filter's weights to float rounding (Detect.VelocityBySumsEqualsTheFiltersWeights).
void fit_run(const Signal& s, size_t start, size_t end, std::span<const FitOutput> outputs, FitScratch& f) {
  if (end - start < 2) return;
  size_t h_max = 0;
  bool second = false;
  for (const FitOutput& o : outputs) {
    h_max = std::max(h_max, static_cast<size_t>(o.scales->h));
    second |= o.acceleration != nullptr;
  }
  constexpr size_t kBlock = 512;
  for (size_t b0 = start; b0 < end; b0 += kBlock) {
    const size_t b1 = std::min(end, b0 + kBlock);
    const size_t lo = b0 > start + h_max ? b0 - h_max : start, hi = std::min(end, b1 + h_max);  // the block's windows lie in [lo, hi)
    const size_t len = hi - lo;
    for (auto& v : f.p) v.resize(len + 1);
    double* const px0 = f.p[0].data();
    double* const py0 = f.p[1].data();
    double* const pz0 = f.p[2].data();
    double* const px1 = f.p[3].data();
    double* const py1 = f.p[4].data();
    double* const pz1 = f.p[5].data();
    double* const px2 = f.p[6].data();
    double* const py2 = f.p[7].data();
    double* const pz2 = f.p[8].data();
    px0[0] = py0[0] = pz0[0] = px1[0] = py1[0] = pz1[0] = px2[0] = py2[0] = pz2[0] = 0;
    const glm::dvec3* d = s.dir.data() + lo;
    const double k0 = double(lo) - double(b0);  // k of the first sample
    for (size_t j = 0; j < len; ++j) {
      const double k = k0 + double(j);
      const double kx = k * d[j].x, ky = k * d[j].y, kz = k * d[j].z;
      px0[j + 1] = px0[j] + d[j].x;
      py0[j + 1] = py0[j] + d[j].y;
      pz0[j + 1] = pz0[j] + d[j].z;
      px1[j + 1] = px1[j] + kx;
      py1[j + 1] = py1[j] + ky;
      pz1[j + 1] = pz1[j] + kz;
      if (second) {
        px2[j + 1] = px2[j] + k * kx;
        py2[j + 1] = py2[j] + k * ky;
        pz2[j + 1] = pz2[j] + k * kz;
      }
    }
    // The sums over [i − w, i + w]: Σ d, and Σ_{|k'|≤w} k'·d[i + k'] = ΔP1 − c·ΔP0 (c: i's k)
    struct Window {
      size_t l, r;
      double c;
      glm::dvec3 a, q, b;  // Σ d, ΔP1, Σ k'·d
    };
    auto window = [&](size_t i, size_t w) {
      Window x{i - w - lo, i + w + 1 - lo, double(i) - double(b0), {}, {}, {}};
      x.a = {px0[x.r] - px0[x.l], py0[x.r] - py0[x.l], pz0[x.r] - pz0[x.l]};
      x.q = {px1[x.r] - px1[x.l], py1[x.r] - py1[x.l], pz1[x.r] - pz1[x.l]};
      x.b = x.q - x.c * x.a;
      return x;
    };
    for (const FitOutput& o : outputs) {
      const LineScales& sc = *o.scales;
      const size_t h = static_cast<size_t>(sc.h);
      auto speed = [&](double scale, double length_sq) {
        return static_cast<float>(o.squared ? scale * scale * length_sq : scale * std::sqrt(length_sq));
      };
      // The velocity over the largest centred window inside the run; at its first and last sample
      // the one-sided difference
      auto line = [&](size_t i) {
        const size_t w = std::min({h, i - start, end - 1 - i});
        if (w == 0) {
          const glm::dvec3 step = s.dir[i + (i == start ? 1 : -1)] - s.dir[i];
          return speed(kDeg / s.dt, glm::dot(step, step));
        }
        const glm::dvec3 b = window(i, w).b;
        return speed(sc.by_width[w], glm::dot(b, b));
      };
      // Centres with the full window, [full_from, full_to); the others near the run's start and end
      const size_t full_from = std::max(b0, start + h), full_to = std::max(full_from, std::min(b1, end > h ? end - h : start));
      for (size_t i = b0; i < std::min(b1, full_from); ++i) o.velocity[i] = line(i);
      for (size_t i = std::max(b0, full_to); i < b1; ++i) o.velocity[i] = line(i);
      const double scale = sc.by_width[h], m = sc.m, a_sq = sc.acceleration * sc.acceleration;
      for (size_t i = full_from; i < full_to; ++i) {
        const Window x = window(i, h);
        o.velocity[i] = speed(scale, glm::dot(x.b, x.b));
        if (o.acceleration) {
          // Σ k'²·d = ΔP2 − 2c·ΔP1 + c²·ΔP0; the parabola's curvature from Σ (k'² − m)·d, squared
          const glm::dvec3 p2(px2[x.r] - px2[x.l], py2[x.r] - py2[x.l], pz2[x.r] - pz2[x.l]);
          const glm::dvec3 curvature = p2 - 2 * x.c * x.q + (x.c * x.c - m) * x.a;
          o.acceleration[i] = static_cast<float>(a_sq * glm::dot(curvature, curvature));
        }
      }
    }
  }
}

// The outputs over every run of valid samples.
void fit_runs(const Signal& s, std::span<const FitOutput> outputs) {
  FitScratch scratch;
  for (size_t start = 0; start < s.n;) {
    if (!s.valid[start]) {
      ++start;
      continue;
    }
    fit_run(s, start, s.run_end[start], outputs, scratch);
    start = s.run_end[start];
  }
}

// A window's half-width in samples: at least 1, at most 256 (a 40 ms window reaches that only above
// 12.8 kHz; a clock in the wrong unit — microseconds read as seconds — must not make the weights'
// table, O(h²), and the filter, O(h) per sample, explode).
int half_width(double window_s, double dt) {
  const double h = 0.5 * window_s / dt;
  return std::isfinite(h) ? std::clamp(static_cast<int>(std::lround(std::min(h, 1e6))), 1, 256) : 1;
}

// Lost runs → blinks (or undefined, when too long), widened over the lid's artefacts: `artefact(i)`
// says whether a valid sample next to a loss still belongs to it.
template <typename Artefact>
void label_blinks(const Signal& s, const EventParams& p, Artefact&& artefact, std::vector<EventLabel>& out) {
  const size_t flank = static_cast<size_t>(std::lround(p.blink_flank_s / s.dt));
  for (size_t i = 0; i < s.n;) {
    if (s.valid[i]) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < s.n && !s.valid[j]) ++j;
    const double from = i > 0 ? s.t[i - 1] : s.t[i], to = j < s.n ? s.t[j] : s.t[j - 1];
    const bool blink = to - from <= p.max_blink_s + 1e-6;
    const EventLabel label = blink ? EventLabel::blink : EventLabel::undefined;
    for (size_t k = i; k < j; ++k) out[k] = label;
    if (blink) {
      for (size_t k = i, steps = 0; k > 0 && steps < flank && s.valid[k - 1] && artefact(k - 1); --k, ++steps) out[k - 1] = label;
      for (size_t k = j, steps = 0; k < s.n && steps < flank && s.valid[k] && artefact(k); ++k, ++steps) out[k] = label;
    }
    i = j;
  }
}

// A saccade or PSO that begins (ends) within the flank after (before) a blink is the lid's
// movement: the blink takes it in, with the samples between.
void absorb_lid_saccades(const Signal& s, const EventParams& p, std::vector<EventLabel>& labels) {
  const size_t flank = static_cast<size_t>(std::lround(p.lid_saccade_s / s.dt));
  auto moving = [&](size_t k) { return labels[k] == EventLabel::saccade || labels[k] == EventLabel::pso; };
  for (size_t i = 0; i < s.n;) {
    if (labels[i] != EventLabel::blink) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < s.n && labels[j] == EventLabel::blink) ++j;
    // Before: the earliest moving sample within the flank, then back to its run's start
    size_t first = i;
    for (size_t k = i, steps = 0; k > 0 && steps < flank && s.valid[k - 1]; --k, ++steps)
      if (moving(k - 1)) first = k - 1;
    while (first > 0 && first < i && moving(first - 1)) --first;
    // After: the last moving sample within the flank, then on to its run's end
    size_t last = j;  // one past
    for (size_t k = j, steps = 0; k < s.n && steps < flank && s.valid[k]; ++k, ++steps)
      if (moving(k)) last = k + 1;
    while (last > j && last < s.n && moving(last)) ++last;
    for (size_t k = first; k < i; ++k) labels[k] = EventLabel::blink;
    for (size_t k = j; k < last; ++k) labels[k] = EventLabel::blink;
    i = std::max(last, j);
  }
}

// Whether a pupil is far from the recording's median (the lid covering it); false without pupils.
// (The median is found at the first test: only recordings with losses next to valid samples ask.)
class PupilTest {
 public:
  PupilTest(const Recording& r, const Signal& s, double deviation) : r_(r), s_(s), deviation_(deviation) {}
  bool operator()(size_t i) {
    if (!median_) {
      std::vector<float> p = s_.valid_pupils;
      median_ = NAN;
      if (!p.empty()) {
        auto mid = p.begin() + p.size() / 2;
        std::nth_element(p.begin(), mid, p.end());
        median_ = *mid;
      }
    }
    const double m = *median_;
    const float pupil = r_.samples[i].pupil;
    return std::isfinite(m) && m > 0 && std::isfinite(pupil) && std::abs(pupil - m) > deviation_ * m;
  }

 private:
  const Recording& r_;
  const Signal& s_;
  double deviation_;
  std::optional<double> median_;
};

bool free_sample(const std::vector<EventLabel>& labels, const Signal& s, size_t i) {
  return s.valid[i] && !s.noise[i] && labels[i] == EventLabel::undefined;
}

// Nyström & Holmqvist 2010: saccades and PSOs into `labels` (blinks already there).
// The median and the scaled median absolute deviation (1.4826·MAD: the standard deviation of
// normal data) of the finite values in a window of `window` samples around each block of
// about window/8 samples (the power of two at most that) (the window kept whole near the ends), from a sliding histogram of 0.25 °/s
// bins: O(1) per sample plus one search per block. Windows with fewer than 16 finite values take
// the whole recording's.
struct LocalStatistics {
  size_t block = 1;
  std::vector<double> median, mad;  // per block: sample i has block i / block
};

double median_of(std::vector<double> x) {
  x.erase(std::remove_if(x.begin(), x.end(), [](double d) { return !std::isfinite(d); }), x.end());
  if (x.empty()) return NAN;
  auto mid = x.begin() + x.size() / 2;
  std::nth_element(x.begin(), mid, x.end());
  return *mid;
}

class VelocityHistogram {
 public:
  static constexpr double kBin = 0.25;
  static constexpr uint16_t kBins = 4096;   // 0 … 1024 °/s; faster in the last bin
  static constexpr uint16_t kNone = kBins;  // not finite: counted in a bin of its own, outside the statistics
  // Each velocity's bin, once (a sample is added and later removed)
  static std::vector<uint16_t> bins(const std::vector<float>& v) {
    std::vector<uint16_t> out(v.size());
    for (size_t i = 0; i < v.size(); ++i)
      out[i] = std::isfinite(v[i]) ? static_cast<uint16_t>(std::clamp(v[i] * float(1 / kBin), 0.0f, float(kBins - 1))) : kNone;
    return out;
  }
  // Adds (sign +1) or removes (−1) the samples [from, to), without a branch
  void add(const uint16_t* bin, size_t from, size_t to, long sign) {
    long none = 0;
    for (size_t i = from; i < to; ++i) {
      counts_[bin[i]] += sign;
      none += bin[i] == kNone;
    }
    total_ += sign * (static_cast<long>(to - from) - none);
  }
  size_t total() const { return static_cast<size_t>(total_); }
  // {median, 1.4826·MAD}, in °/s (bin centres)
  std::pair<double, double> median_mad() const {
    const long half = (total_ + 1) / 2;
    long seen = 0;
    size_t m = 0;
    while (m + 1 < kBins && seen + counts_[m] < half) seen += counts_[m++];
    long inside = counts_[m];
    size_t d = 0;
    while (inside < half && d < kBins) {
      ++d;
      if (m >= d) inside += counts_[m - d];
      if (m + d < kBins) inside += counts_[m + d];
    }
    return {(m + 0.5) * kBin, 1.4826 * d * kBin};
  }

 private:
  std::array<long, kBins + 1> counts_{};
  long total_ = 0;
};

LocalStatistics local_statistics(const std::vector<float>& v, size_t window) {
  const size_t n = v.size();
  LocalStatistics out;
  if (n == 0) return out;
  const std::vector<uint16_t> bins = VelocityHistogram::bins(v);
  // The whole recording's, for windows with too few velocities (computed only where one is)
  std::optional<std::pair<double, double>> all;
  auto whole = [&] {
    if (!all) {
      auto h = std::make_unique<VelocityHistogram>();
      h->add(bins.data(), 0, n, +1);
      all = h->total() ? h->median_mad() : std::pair<double, double>{NAN, NAN};
    }
    return *all;
  };
  window = std::min(window, n);
  out.block = std::bit_floor(std::max<size_t>(1, window / 8));  // a power of two: a sample's block is a shift
  auto hist = std::make_unique<VelocityHistogram>();
  size_t lo = 0, hi = 0;  // the histogram holds v[lo, hi)
  for (size_t b0 = 0; b0 < n; b0 += out.block) {
    const size_t b1 = std::min(n, b0 + out.block), centre = (b0 + b1) / 2;
    const size_t start = std::min(n - window, centre > window / 2 ? centre - window / 2 : 0), end = start + window;
    if (hi < end) hist->add(bins.data(), hi, end, +1), hi = end;
    if (lo < start) hist->add(bins.data(), lo, start, -1), lo = start;
    const auto [median, mad] = hist->total() >= 16 ? hist->median_mad() : whole();
    out.median.push_back(median);
    out.mad.push_back(mad);
  }
  return out;
}

// Thresholds per sample (°/s), stored per block of 2^shift samples: one block for nh/nhp, the
// local statistics' blocks for nhr (a shift, not a division, per lookup).
struct SampleThresholds {
  unsigned shift = 63;
  std::vector<float> peaks, onsets, coarse_peaks;  // per block; coarse: the smoother velocity's peak threshold (empty: none)
  float peak(size_t i) const { return peaks[i >> shift]; }
  float onset(size_t i) const { return onsets[i >> shift]; }
  float coarse_peak(size_t i) const { return coarse_peaks[i >> shift]; }
};

// nh's saccades, PSOs after them. `onset_above`: a saccade's first sample is the first above the
// onset threshold (nhr) rather than the last below it (the paper's local minimum, nh and nhp).
void label_saccades_nh(const Signal& s, const EventParams& p, const std::vector<float>& v, const SampleThresholds& th,
                       const std::vector<float>& coarse, double pso_window_s, bool onset_above, std::vector<EventLabel>& labels) {
  const size_t n = s.n;
  const size_t pso_window = static_cast<size_t>(std::lround(pso_window_s / s.dt));
  const size_t noise_window = static_cast<size_t>(std::max(1L, std::lround(p.local_noise_s / s.dt)));
  const double min_saccade = p.min_saccade_s - 1e-6;
  auto usable = [&](size_t i) { return free_sample(labels, s, i) && std::isfinite(v[i]); };
  for (size_t i = 0; i < n; ++i) {
    if (!usable(i)) continue;
    size_t p1 = i;
    if (v[i] > th.peak(i)) {
      // A peak: samples above the peak threshold from i
      while (p1 + 1 < n && usable(p1 + 1) && v[p1 + 1] > th.peak(p1 + 1)) ++p1;
    } else if (!coarse.empty() && coarse[i] > th.coarse_peak(i)) {
      // A peak of the smoother velocity only (a small saccade in noise): the saccade is around the
      // fine velocity's largest sample under it, if that is above the onset threshold
      size_t c1 = i, m = i;
      while (c1 + 1 < n && usable(c1 + 1) && coarse[c1 + 1] > th.coarse_peak(c1 + 1)) {
        ++c1;
        if (v[c1] > v[m]) m = c1;
      }
      if (!(v[m] >= th.onset(m))) {
        i = c1;
        continue;
      }
      i = p1 = m;
      while (p1 + 1 < n && usable(p1 + 1) && v[p1 + 1] > th.peak(p1 + 1)) ++p1;
    } else {
      continue;
    }
    // Onset: back to the first sample below the onset threshold (the threshold crossing; waiting
    // for the local minimum as well starts saccades 2 ms early on the IRF data)
    size_t a = i;
    while (a > 0 && usable(a - 1) && v[a] >= th.onset(a)) --a;
    const double onset = th.onset(a), peak = th.peak(a);
    // Offset threshold from the local noise before the onset
    double sum = 0, sum2 = 0;
    size_t count = 0;
    for (size_t k = a, steps = 0; k > 0 && steps < noise_window && usable(k - 1); --k, ++steps) {
      sum += v[k - 1];
      sum2 += double(v[k - 1]) * v[k - 1];
      ++count;
    }
    double offset = onset;
    if (count >= 2) {
      const double mean = sum / count, sd = std::sqrt(std::max(0.0, sum2 / count - mean * mean));
      offset = 0.7 * onset + 0.3 * (mean + 3 * sd);
    }
    // Offset: forward to the first sample below the offset threshold, or to the first velocity
    // trough below the peak threshold (nhr: below `saccade_trough` of the saccade's own peak
    // velocity), whichever comes first: the oscillation after the trough is the PSO, not the saccade
    double trough = peak;
    if (onset_above && p.saccade_trough > 0) {
      float top = 0;
      for (size_t k = a; k <= p1; ++k) top = std::max(top, v[k]);
      trough = p.saccade_trough * top;
    }
    size_t b = p1;
    while (b + 1 < n && usable(b + 1) && v[b] >= offset && !(v[b] < trough && v[b + 1] > v[b])) ++b;
    const double duration = (b - a + 1) * s.dt;
    if (duration < min_saccade) {
      i = b;
      continue;
    }
    // (nhr: the crossing's sample below the threshold is the fixation's: with the 10 ms filter the
    // saccade's rise reaches it early, and saccades began 1.7 ms before the coders' on average over
    // IRF and Lund. Which saccades are found, their duration test and offset threshold, stay nh's.)
    const size_t first = onset_above && a < i && v[a] < onset ? a + 1 : a;
    for (size_t k = first; k <= b; ++k) labels[k] = EventLabel::saccade;
    // PSO: velocity above the offset threshold again within the window after the offset
    size_t last_peak = b;
    for (size_t k = b + 1; k < n && k <= b + pso_window && usable(k); ++k)
      if (v[k] > offset) last_peak = k;
    if (last_peak > b) {
      size_t e = last_peak;
      while (e + 1 < n && usable(e + 1) && (v[e] >= offset || v[e + 1] < v[e])) ++e;
      for (size_t k = b + 1; k <= e; ++k) labels[k] = EventLabel::pso;
      b = e;
    }
    i = b;
  }
}

void line_velocity(const Signal& s, int h, std::vector<float>& velocity) {
  const LineScales scales(h, s.dt);
  velocity.assign(s.n, NAN);
  const FitOutput out{&scales, velocity.data()};
  fit_runs(s, {&out, 1});
}

// Pursuit in the intersaccadic runs (nhp): a least-squares line's velocity over a longer window.
void label_pursuit(const Signal& s, const PursuitParams& pursuit, std::vector<EventLabel>& labels) {
  const LineScales scales(half_width(pursuit.window_s, s.dt), s.dt);
  std::vector<float> slow(s.n, NAN);  // squared speeds, compared with the squared threshold
  const FitOutput squared_speed{&scales, slow.data(), nullptr, true};
  fit_runs(s, {&squared_speed, 1});
  const double min_pursuit = pursuit.min_s - 1e-6, threshold = pursuit.velocity_deg_s * pursuit.velocity_deg_s;
  for (size_t i = 0; i < s.n;) {
    if (!(free_sample(labels, s, i) && slow[i] > threshold)) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < s.n && free_sample(labels, s, j) && slow[j] > threshold) ++j;
    const double duration = (j - i) * s.dt;
    const double travelled = angle_between_deg(s.dir[i], s.dir[j - 1]);
    if (duration >= min_pursuit && travelled >= pursuit.travel_fraction * pursuit.velocity_deg_s * duration)
      for (size_t k = i; k < j; ++k) labels[k] = EventLabel::pursuit;
    i = j;
  }
}

// Each stretch [start, end) of free samples (valid, not noise, not yet labelled) without a gap in
// time: the intersaccadic intervals, as the pursuit and fixation passes see them.
template <typename Fn>
void for_each_free_interval(const Signal& s, const std::vector<EventLabel>& labels, Fn&& fn) {
  for (size_t start = 0; start < s.n;) {
    if (!free_sample(labels, s, start)) {
      ++start;
      continue;
    }
    size_t end = start;
    while (end < s.n && free_sample(labels, s, end) && s.run_start[end] == s.run_start[start]) ++end;
    fn(start, end);
    start = end;
  }
}

// Pursuit in the intersaccadic intervals (nhr): the least-squares line's velocity over a window
// that stays inside each interval (a window reaching into the saccade before or after would take
// its movement for pursuit).
void label_pursuit_in_intervals(const Signal& s, const EventParams& p, std::vector<EventLabel>& labels) {
  const PursuitParams& pursuit = p.slow_pursuit;
  const LineScales scales(half_width(pursuit.window_s, s.dt), s.dt);
  FitScratch scratch;
  std::vector<float> slow(s.n, NAN);  // squared speeds (°/s)², compared with squared thresholds
  const FitOutput squared_speed{&scales, slow.data(), nullptr, true};
  // The wide window's speed rises before a pursuit begins and falls after it ends: a run's edges
  // are set by a shorter window's speed (computed only for the intervals that hold a run)
  const LineScales edge_scales(half_width(p.pursuit_edge_s, s.dt), s.dt);
  std::vector<float> edge(s.n, NAN);
  const FitOutput edge_speed{&edge_scales, edge.data(), nullptr, true};
  const double min_pursuit = pursuit.min_s - 1e-6;
  const double keep = p.pursuit_keep, relax = p.context_relax, cos_min = p.context_cos, relax_min = p.context_min_fraction;
  const size_t settle = static_cast<size_t>(std::lround(p.settle_s / s.dt));
  auto moving = [&](size_t k) { return labels[k] == EventLabel::saccade || labels[k] == EventLabel::pso; };
  // Candidate runs of one free stretch [start, end) above `velocity`, extended while above
  // keep·velocity; returns whether any became pursuit
  auto label_runs_above = [&](size_t start, size_t end, double velocity, double min_s, const glm::dvec3* along) {
    bool labelled = false;
    for (size_t i = start; i < end;) {
      if (!(slow[i] > velocity * velocity)) {
        ++i;
        continue;
      }
      size_t j = i;
      const double kept = keep * keep * velocity * velocity;
      while (j < end && slow[j] > kept) ++j;
      while (i > start && slow[i - 1] > kept) --i;
      size_t a = i, b = j;  // the run, its edges where the shorter window's speed passes keep·velocity
      if (p.pursuit_edge_s > 0) {
        if (!std::isfinite(edge[start])) fit_run(s, start, end, {&edge_speed, 1}, scratch);
        while (a < b && !(edge[a] > kept)) ++a;
        while (b > a && !(edge[b - 1] > kept)) --b;
      }
      const bool after_saccade = start > 0 && moving(start - 1);
      const size_t from = after_saccade ? std::max(a, std::min(b, start + settle)) : a;  // the eye settling after a saccade does not count
      const double duration = b > from ? (b - from) * s.dt : 0.0;
      bool ok =
          b > a && duration >= min_s && angle_between_deg(s.dir[a], s.dir[b - 1]) >= pursuit.travel_fraction * velocity * (b - a) * s.dt;
      if (ok && along) {
        const glm::dvec3 d = s.dir[b - 1] - s.dir[a];
        ok = glm::dot(d, *along) >= cos_min * glm::length(d) * glm::length(*along);
      }
      if (ok) {
        for (size_t k = a; k < b; ++k) labels[k] = EventLabel::pursuit;
        labelled = true;
      }
      i = j;
    }
    return labelled;
  };
  // The speeds of an interval, once, and only of one long enough to hold a pursuit of `min_s` (a
  // pursuit's duration lies inside its interval; the stretches the context pass sees are whole
  // intervals where the first pass labelled nothing)
  auto fit = [&](size_t start, size_t end, double min_s) {
    if (double(end - start) * s.dt < min_s || std::isfinite(slow[start])) return;
    fit_run(s, start, end, {&squared_speed, 1}, scratch);
  };
  for_each_free_interval(s, labels, [&](size_t start, size_t end) {
    fit(start, end, min_pursuit);
    label_runs_above(start, end, pursuit.velocity_deg_s, min_pursuit, nullptr);
  });
  if (relax <= 0) return;
  // Context: pursuit continues across catch-up saccades; a slower stretch next to a pursuit (across
  // at most a saccade and its PSO) that moves the same way is pursuit too
  const size_t context = static_cast<size_t>(std::lround(p.context_s / s.dt));
  auto pursuit_direction = [&](size_t k) {  // the pursuit run through k: its net movement
    size_t a = k, b = k;
    while (a > 0 && labels[a - 1] == EventLabel::pursuit) --a;
    while (b + 1 < s.n && labels[b + 1] == EventLabel::pursuit) ++b;
    return s.dir[b] - s.dir[a];
  };
  for (int pass = 0; pass < 4; ++pass) {
    bool changed = false;
    for_each_free_interval(s, labels, [&](size_t start, size_t end) {
      // The pursuit next to this stretch, across at most `context` saccade or PSO samples, before or after
      std::optional<glm::dvec3> along;
      size_t k = start, steps = 0;
      while (k > 0 && steps < context && moving(k - 1)) --k, ++steps;
      if (k > 0 && labels[k - 1] == EventLabel::pursuit) along = pursuit_direction(k - 1);
      for (k = end, steps = 0; !along && k < s.n && steps < context && moving(k); ++k, ++steps) {}
      if (!along && k < s.n && labels[k] == EventLabel::pursuit) along = pursuit_direction(k);
      if (!along) return;
      fit(start, end, relax_min * min_pursuit);
      changed |= label_runs_above(start, end, relax * pursuit.velocity_deg_s, relax_min * min_pursuit, &*along);
    });
    if (!changed) break;
  }
}

// The free valid runs left become fixations (those shorter than `min_s` stay undefined). A gap in
// the samples' times ends a fixation: the time without samples is lost, not fixated.
void label_fixations(const Signal& s, double min_s, std::vector<EventLabel>& labels) {
  for_each_free_interval(s, labels, [&](size_t start, size_t end) {
    if ((end - start) * s.dt >= min_s - 1e-6) std::fill(labels.begin() + start, labels.begin() + end, EventLabel::fixation);
  });
}

}  // namespace

namespace {

// The runs of labels as events, with amplitudes, peak velocities and positions.
void list_events(const Signal& s, EventDetection& out) {
  const std::vector<float>& v = out.velocity_deg_s;
  const std::vector<double>& t = s.t;
  out.events.clear();
  // The runs of one label, split where the samples' times jump (a gap in the recording)
  std::vector<LabelledEvent> runs;
  for (const LabelledEvent& run : label_runs(out.labels, t)) {
    LabelledEvent part = run;
    for (size_t k = run.first + 1; k <= run.last; ++k)
      if (s.valid[k - 1] && s.valid[k] && s.run_start[k] != s.run_start[k - 1]) {
        part.last = k - 1;
        part.offset_s = t[k - 1];
        runs.push_back(part);
        part.first = k;
        part.onset_s = t[k];
      }
    part.last = run.last;
    part.offset_s = run.offset_s;
    runs.push_back(part);
  }
  for (const LabelledEvent& run : runs) {
    if (run.label == EventLabel::undefined) continue;
    DetectedEvent e;
    e.label = run.label;
    e.first = run.first;
    e.last = run.last;
    e.onset_s = run.onset_s;
    e.duration_s = run.duration_s() + s.dt;
    e.peak_velocity_deg_s = NAN;
    e.amplitude_deg = NAN;
    // The first and last valid sample (blinks have none that count)
    size_t a = run.first, b = run.last;
    while (a < b && !s.valid[a]) ++a;
    while (b > a && !s.valid[b]) --b;
    if (s.valid[a] && e.label != EventLabel::blink) {
      e.amplitude_deg = angle_between_deg(s.dir[a], s.dir[b]);
      const glm::dvec2 start = GazeGeometry::angles_deg(s.dir[a]), end = GazeGeometry::angles_deg(s.dir[b]);
      e.start_deg = {start.x, -start.y};
      e.end_deg = {end.x, -end.y};
      float peak = 0;
      for (size_t k = a; k <= b; ++k)
        if (std::isfinite(v[k])) peak = std::max(peak, v[k]);
      e.peak_velocity_deg_s = peak;
    }
    out.events.push_back(e);
  }
}

}  // namespace

EventDetection events_from_labels(const Recording& r, const GazeGeometry& g, std::vector<EventLabel> labels) {
  if (labels.size() != r.samples.size()) fail("events_from_labels: {} labels for {} samples", labels.size(), r.samples.size());
  EventDetection out;
  const Signal s = prepare(r, g);
  out.sampling_hz = 1 / s.dt;
  line_velocity(s, half_width(EventParams{}.filter_window_s, s.dt), out.velocity_deg_s);
  out.labels = std::move(labels);
  list_events(s, out);
  return out;
}

EventDetection detect_events(const Recording& r, const GazeGeometry& g, EventMethod method, const EventParams& p,
                             const FixationParams& fixation) {
  validate(p);
  EventDetection out;
  out.method = method;
  Signal s = prepare(r, g, method == EventMethod::nhr ? p.max_dropout_s : 0);
  out.sampling_hz = 1 / s.dt;
  const bool adaptive = method == EventMethod::nh || method == EventMethod::nhp || method == EventMethod::nhr;
  // The velocity by Savitzky–Golay (its first derivative is the least-squares line's), and for nh,
  // nhp, nhr its squared acceleration (the noise test) and the smoother velocity that finds small
  // saccades in noise (none when off), from one set of sums
  std::vector<float> acceleration, coarse;
  const double filter_window = method == EventMethod::nhr ? p.robust_filter_window_s : p.filter_window_s;
  const LineScales fine(half_width(filter_window, s.dt), s.dt), smooth(half_width(p.detection_window_s, s.dt), s.dt);
  out.velocity_deg_s.assign(s.n, NAN);
  std::vector<FitOutput> fits{{&fine, out.velocity_deg_s.data()}};
  if (adaptive) {
    acceleration.assign(s.n, NAN);
    fits[0].acceleration = acceleration.data();
    if (p.detection_window_s > 0) {
      coarse.assign(s.n, NAN);
      fits.push_back({&smooth, coarse.data()});
    }
  }
  fit_runs(s, fits);
  const std::vector<float>& v = out.velocity_deg_s;
  out.labels.assign(s.n, EventLabel::undefined);
  auto& labels = out.labels;
  // The blink rule's pupil test (not for ivt/idt, whose lost samples are their blinks)
  std::optional<PupilTest> pupil;
  if (method != EventMethod::ivt && method != EventMethod::idt && method != EventMethod::ivvt) pupil.emplace(r, s, p.pupil_deviation);

  switch (method) {
    case EventMethod::ivt:
    case EventMethod::idt: {
      // Run here, not taken from a caller's earlier run, so that a detection (and its time) is self-contained
      const FixationResult f = method == EventMethod::ivt ? detect_ivt(r, g, fixation) : detect_idt(r, g, fixation);
      labels = labels_from_fixations(r, f);
      break;
    }
    case EventMethod::ivvt: {
      // The causal filter that replay and view follow the eye with, sample by sample as a tracker
      // delivers them: its fixations, pursuits, the rest of the valid samples saccades
      FixationTracker tracker(FixationMethod::ivvt, fixation, g);
      for (size_t i = 0; i < s.n; ++i) {
        tracker.push(r.samples[i]);
        labels[i] = !s.valid[i]             ? EventLabel::blink
                    : tracker.in_pursuit()  ? EventLabel::pursuit
                    : tracker.in_fixation() ? EventLabel::fixation
                                            : EventLabel::saccade;
      }
      break;
    }
    case EventMethod::nh:
    case EventMethod::nhp:
    case EventMethod::nhr: {
      // Physiologically impossible samples are noise: out of the threshold's statistics
      std::vector<float> clean = v;
      const double max_acceleration_sq = p.max_acceleration_deg_s2 * p.max_acceleration_deg_s2;  // (the accelerations are squared)
      for (size_t i = 0; i < s.n; ++i)
        if (s.valid[i] && (v[i] > p.max_velocity_deg_s || acceleration[i] > max_acceleration_sq)) {
          s.noise[i] = true;
          clean[i] = NAN;
        }
      // (the smoother velocity: not where the velocity is noise)
      if (!coarse.empty())
        for (size_t i = 0; i < s.n; ++i)
          if (s.noise[i]) coarse[i] = NAN;
      SampleThresholds th;
      if (method == EventMethod::nhr) {
        // Local, robust thresholds (median and MAD per window)
        const size_t window = std::max<size_t>(8, static_cast<size_t>(std::lround(p.threshold_window_s / s.dt)));
        const LocalStatistics fine = local_statistics(clean, window);
        th.shift = static_cast<unsigned>(std::countr_zero(fine.block));
        th.peaks.resize(fine.median.size());
        th.onsets.resize(fine.median.size());
        std::vector<double> block_peak(fine.median.size()), block_onset(fine.median.size());
        for (size_t b = 0; b < fine.median.size(); ++b) {
          block_peak[b] = std::max(p.min_peak_deg_s, fine.median[b] + p.robust_peak_k * fine.mad[b]);
          block_onset[b] = std::max(0.5 * p.min_peak_deg_s, fine.median[b] + p.robust_onset_k * fine.mad[b]);
          th.peaks[b] = static_cast<float>(block_peak[b]);
          th.onsets[b] = static_cast<float>(block_onset[b]);
        }
        if (!coarse.empty()) {
          const LocalStatistics slow = local_statistics(coarse, window);  // the same blocks
          th.coarse_peaks.resize(slow.median.size());
          for (size_t b = 0; b < slow.median.size(); ++b)
            th.coarse_peaks[b] = static_cast<float>(std::max(p.min_peak_deg_s, slow.median[b] + p.robust_peak_k * slow.mad[b]));
        }
        // Reported: the median over the blocks (all of one size but the last)
        out.peak_threshold_deg_s = median_of(std::move(block_peak));
        out.onset_threshold_deg_s = median_of(std::move(block_onset));
      } else {
        // The paper's iteration, floored as nhr's thresholds are: a noise-free recording's σ is 0,
        // and 1e-12 °/s would make every sample a saccade (issue 36's finding 16)
        const std::pair<double, double> found = adaptive_velocity_thresholds(clean, p.initial_peak_deg_s);
        const double peak = std::max(found.first, p.min_peak_deg_s), onset = std::max(found.second, 0.5 * p.min_peak_deg_s);
        th.peaks = {static_cast<float>(peak)};
        th.onsets = {static_cast<float>(onset)};
        if (!coarse.empty())
          th.coarse_peaks = {
              static_cast<float>(std::max(adaptive_velocity_thresholds(coarse, p.initial_peak_deg_s).first, p.min_peak_deg_s))};
        out.peak_threshold_deg_s = peak;
        out.onset_threshold_deg_s = onset;
      }
      // Noise next to a loss is the lid's (a blink); elsewhere it stays undefined
      label_blinks(
          s, p, [&](size_t i) { return s.noise[i] || !(v[i] < th.onset(i)) || (*pupil)(i); }, labels);
      label_saccades_nh(s, p, clean, th, coarse, method == EventMethod::nhr ? p.robust_pso_window_s : p.pso_window_s,
                        method == EventMethod::nhr, labels);
      absorb_lid_saccades(s, p, labels);
      if (method == EventMethod::nhp) label_pursuit(s, p.pursuit, labels);
      if (method == EventMethod::nhr) label_pursuit_in_intervals(s, p, labels);
      label_fixations(s, p.min_fixation_s, labels);
      break;
    }
    case EventMethod::ek: {
      // Velocities per axis (degrees) from a 5-sample window; thresholds from median estimators
      std::vector<glm::dvec2> angle(s.n, glm::dvec2(NAN)), vel(s.n, glm::dvec2(NAN));
      for (size_t i = 0; i < s.n; ++i)
        if (s.valid[i]) angle[i] = GazeGeometry::angles_deg(s.dir[i]);
      std::vector<double> vx, vy;
      vx.reserve(s.n);
      vy.reserve(s.n);
      for (size_t i = 0; i < s.n; ++i) {
        if (!s.valid[i]) continue;
        const size_t before = i - s.run_start[i], after = s.run_end[i] - 1 - i;
        if (before >= 2 && after >= 2)
          vel[i] = (angle[i + 2] + angle[i + 1] - angle[i - 1] - angle[i - 2]) / (6 * s.dt);
        else if (before >= 1 && after >= 1)
          vel[i] = (angle[i + 1] - angle[i - 1]) / (2 * s.dt);
        else if (after >= 1)  // a run's edge (next to a loss): one-sided
          vel[i] = (angle[i + 1] - angle[i]) / s.dt;
        else if (before >= 1)
          vel[i] = (angle[i] - angle[i - 1]) / s.dt;
        else
          continue;
        vx.push_back(vel[i].x);
        vy.push_back(vel[i].y);
      }
      auto median = [](std::vector<double> x) {
        if (x.empty()) return 0.0;
        auto mid = x.begin() + x.size() / 2;
        std::nth_element(x.begin(), mid, x.end());
        return *mid;
      };
      auto sigma = [&](const std::vector<double>& x) {
        std::vector<double> sq(x.size());
        for (size_t i = 0; i < x.size(); ++i) sq[i] = x[i] * x[i];
        const double m = median(x);
        return std::sqrt(std::max(median(sq) - m * m, 1e-12));
      };
      const glm::dvec2 eta = p.ek_lambda * glm::dvec2(sigma(vx), sigma(vy));
      out.peak_threshold_deg_s = out.onset_threshold_deg_s = 0.5 * (eta.x + eta.y);
      auto outside = [&](size_t i) {
        const glm::dvec2 q = vel[i] / eta;
        return glm::dot(q, q) > 1;  // NaN: false
      };
      label_blinks(
          s, p, [&](size_t i) { return outside(i) || (*pupil)(i); }, labels);
      const size_t min_samples = std::max<size_t>(1, static_cast<size_t>(std::lround(p.ek_min_saccade_s / s.dt)));
      for (size_t i = 0; i < s.n;) {
        if (!(free_sample(labels, s, i) && outside(i))) {
          ++i;
          continue;
        }
        size_t j = i;
        while (j < s.n && free_sample(labels, s, j) && outside(j)) ++j;
        if (j - i >= min_samples)
          for (size_t k = i; k < j; ++k) labels[k] = EventLabel::saccade;
        i = j;
      }
      label_fixations(s, 0, labels);
      break;
    }
  }

  list_events(s, out);
  return out;
}

std::string events_tsv(const EventDetection& d, const Recording& r) {
  const double t0 = r.samples.empty() ? 0 : r.samples.front().t_s;
  auto cell = [](double x) { return std::isfinite(x) ? fmt::format("{:.4f}", x) : std::string("n/a"); };
  std::string out = "onset\tduration\ttrial_type\tamplitude_deg\tpeak_velocity_deg_s\tstart_x_deg\tstart_y_deg\tend_x_deg\tend_y_deg\n";
  for (const DetectedEvent& e : d.events)
    out += fmt::format("{:.6f}\t{:.6f}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\n", e.onset_s - t0, e.duration_s, to_string(e.label),
                       cell(e.amplitude_deg), std::isfinite(e.peak_velocity_deg_s) ? fmt::format("{:.1f}", e.peak_velocity_deg_s) : "n/a",
                       cell(e.start_deg.x), cell(e.start_deg.y), cell(e.end_deg.x), cell(e.end_deg.y));
  return out;
}

}  // namespace foveal
