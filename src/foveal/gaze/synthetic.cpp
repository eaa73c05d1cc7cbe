// foveal/gaze/synthetic.cpp — synthetic recordings with known events (see synthetic.h).
#include "foveal/gaze/synthetic.h"

#include "foveal/util/error.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <random>

namespace foveal {

Display synthetic_display() { return Display{53.3, 30.1, 56.5, 1920, 1080}; }

SyntheticSignal::SyntheticSignal(double rate, double start_deg) : rate_hz(rate) {
  if (!(rate > 0 && std::isfinite(rate))) fail("synthetic: rate_hz {} is not a positive number", rate);
  x.push_back(start_deg);
  label.push_back(EventLabel::fixation);
}

void SyntheticSignal::fixation(double seconds) {
  const double at = x.back();
  for (long i = 0, n = std::lround(seconds * rate_hz); i < n; ++i) {
    x.push_back(at);
    label.push_back(EventLabel::fixation);
  }
}

void SyntheticSignal::saccade(double amplitude, double pso_deg) {
  const double from = x.back(), duration = (2.2 * std::abs(amplitude) + 21) / 1000;
  truth.push_back({EventLabel::saccade, x.size() / rate_hz, duration, std::abs(amplitude)});
  const long n = std::max(1L, std::lround(duration * rate_hz));
  for (long i = 1; i <= n; ++i) {
    const double u = double(i) / n;
    x.push_back(from + amplitude * (10 * u * u * u - 15 * u * u * u * u + 6 * u * u * u * u * u));
    label.push_back(EventLabel::saccade);
  }
  if (pso_deg > 0) {
    truth.push_back({EventLabel::pso, x.size() / rate_hz, 0.025, 0});
    const double to = x.back();
    for (long i = 1, m = std::lround(0.025 * rate_hz); i <= m; ++i) {
      const double t = i / rate_hz;
      x.push_back(to + std::copysign(pso_deg, amplitude) * std::exp(-t / 0.010) * std::sin(2 * M_PI * 40 * t));
      label.push_back(EventLabel::pso);
    }
  }
}

void SyntheticSignal::pursuit(double deg_s, double seconds) {
  truth.push_back({EventLabel::pursuit, x.size() / rate_hz, seconds, std::abs(deg_s) * seconds});
  const double from = x.back();
  for (long i = 1, n = std::lround(seconds * rate_hz); i <= n; ++i) {
    x.push_back(from + deg_s * i / rate_hz);
    label.push_back(EventLabel::pursuit);
  }
}

void SyntheticSignal::blink(double seconds) {
  truth.push_back({EventLabel::blink, x.size() / rate_hz, seconds, 0});
  const double at = x.back();
  for (long i = 0, n = std::lround(seconds * rate_hz); i < n; ++i) {
    x.push_back(NAN);
    label.push_back(EventLabel::blink);
  }
  x.push_back(at);
  label.push_back(EventLabel::fixation);
}

Recording SyntheticSignal::recording(const Degradation& d, double t0) const {
  std::mt19937 rng(d.seed);
  std::normal_distribution<double> noise(0, d.noise_rms_deg / std::sqrt(2.0));  // 2-D RMS = noise_rms_deg
  std::vector<bool> lost(x.size(), false);
  if (d.loss_fraction > 0) {
    std::uniform_real_distribution<double> unit(0, 1);
    const double target = d.loss_fraction * x.size();
    double count = 0;
    for (int tries = 0; count < target && tries < 100000; ++tries) {
      const long n = std::max(1L, std::lround(d.burst_s * (0.5 + unit(rng)) * rate_hz));
      const size_t at = static_cast<size_t>(unit(rng) * x.size());
      for (size_t k = at; k < std::min(x.size(), at + n); ++k)
        if (!lost[k]) {
          lost[k] = true;
          ++count;
        }
    }
  }
  const Display display = synthetic_display();
  Recording r;
  r.screen_px = {display.res_x, display.res_y};
  r.samples.reserve(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    GazeSample s;
    s.t_s = t0 + i / rate_hz;
    const double nx = noise(rng), ny = noise(rng);
    if (std::isfinite(x[i]) && !lost[i]) {
      s.valid = true;
      s.direction = glm::normalize(glm::dvec3(std::tan(glm::radians(x[i] + nx)), -std::tan(glm::radians(ny)), 1.0));
      s.px = {0.5 * display.res_x, 0.5 * display.res_y};
    }
    r.samples.push_back(s);
  }
  return r;
}

SyntheticSignal synthetic_viewing(double seconds, double rate_hz, bool with_pursuit, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  SyntheticSignal s(rate_hz, 0);
  double next_blink = 3;
  int k = 0;
  while (s.x.size() < seconds * rate_hz) {
    const double t = s.x.size() / rate_hz;
    if (t >= next_blink) {
      s.fixation(0.2);
      s.blink(0.08 + 0.1 * unit(rng));
      next_blink += 3;
    }
    s.fixation(0.15 + 0.25 * unit(rng));
    // Amplitudes 1–15°, log-uniform, toward the centre when far out
    const double amplitude = std::exp(unit(rng) * std::log(15.0));
    const double sign = s.x.back() > 8 ? -1 : s.x.back() < -8 ? 1 : (unit(rng) < 0.5 ? -1 : 1);
    s.saccade(sign * amplitude, k++ % 2 ? 0.3 : 0);
    if (with_pursuit && unit(rng) < 0.4) {
      const double speed = (4 + 11 * unit(rng)) * (s.x.back() > 0 ? -1 : 1);
      s.fixation(0.1);
      s.pursuit(speed, 0.3 + 0.5 * unit(rng));
      s.saccade(std::copysign(1 + 1.5 * unit(rng), speed));  // a catch-up saccade of 1–2.5°, then on
      s.pursuit(speed, 0.3);
    }
  }
  s.fixation(0.2);
  return s;
}

}  // namespace foveal
