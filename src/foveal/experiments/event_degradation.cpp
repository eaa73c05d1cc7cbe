// foveal/experiments/event_degradation.cpp — detectors against synthetic truth under noise and loss.
#include "foveal/experiments/event_degradation.h"

#include "foveal/gaze/synthetic.h"
#include "foveal/util/error.h"
#include "foveal/util/parse.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace foveal {

void validate(const DegradationParams& p) {
  require_positive(p.seconds, "seconds");
  if (p.seconds > 3600) fail("seconds: {} is more than an hour of synthetic samples per condition", p.seconds);
  if (p.rates_hz.empty() || p.noise_rms_deg.empty() || p.loss_fractions.empty() || p.methods.empty())
    fail("rates_hz, noise_rms_deg, loss_fractions, methods: each needs at least one value");
  for (double r : p.rates_hz)
    if (!(r >= 50 && r <= 10000)) fail("rates_hz: {} Hz is outside 50–10000 Hz", r);
  for (double n : p.noise_rms_deg)
    if (!(n >= 0 && n <= 5)) fail("noise_rms_deg: {}° is outside 0–5°", n);
  for (double l : p.loss_fractions)
    if (!(l >= 0 && l <= 0.5)) fail("loss_fractions: {} is outside 0–0.5", l);
  require_positive(p.burst_s, "burst_s");
}

std::vector<DegradationRow> run_event_degradation(const DegradationParams& p) {
  validate(p);
  std::vector<DegradationRow> rows;
  const GazeGeometry geometry(synthetic_display(), {synthetic_display().res_x, synthetic_display().res_y});
  for (double rate : p.rates_hz) {
    const SyntheticSignal signal = synthetic_viewing(p.seconds, rate, true, p.seed);
    const size_t saccades =
        std::count_if(signal.truth.begin(), signal.truth.end(), [](const SyntheticEvent& e) { return e.label == EventLabel::saccade; });
    for (double noise : p.noise_rms_deg)
      for (double loss : p.loss_fractions) {
        const Recording r = signal.recording({noise, loss, p.burst_s, p.seed + 1});
        std::vector<double> t(r.samples.size());
        for (size_t i = 0; i < t.size(); ++i) t[i] = r.samples[i].t_s;
        for (EventMethod m : p.methods) {
          const EventDetection d = detect_events(r, geometry, m, EventParams{}, FixationParams{});
          const Evaluation e = evaluate_labels(d.labels, signal.label, t);
          DegradationRow row;
          row.rate_hz = rate;
          row.noise_rms_deg = noise;
          row.loss_fraction = loss;
          row.method = m;
          row.saccade_f1 = e.of(EventLabel::saccade).f1;
          row.saccade_kappa = e.of(EventLabel::saccade).kappa;
          row.pso_kappa = e.of(EventLabel::pso).kappa;
          row.fixation_kappa = e.of(EventLabel::fixation).kappa;
          row.pursuit_kappa = e.of(EventLabel::pursuit).kappa;
          row.pursuit_f1 = e.of(EventLabel::pursuit).f1;
          row.samples = t.size();
          row.saccades = saccades;
          rows.push_back(row);
        }
      }
  }
  return rows;
}

std::string degradation_markdown(const DegradationParams& p, const std::vector<DegradationRow>& rows) {
  std::string out;
  auto table = [&](EventMethod m, const char* what, double DegradationRow::*field) {
    out += fmt::format("\n{} — {}\n\n| noise RMS | lost |", to_string(m), what);
    for (double r : p.rates_hz) out += fmt::format(" {:.0f} Hz |", r);
    out += "\n|---:|---:|";
    for (size_t k = 0; k < p.rates_hz.size(); ++k) out += "---:|";
    out += "\n";
    for (double noise : p.noise_rms_deg)
      for (double loss : p.loss_fractions) {
        out += fmt::format("| {:.2f}° | {:.0f} % |", noise, 100 * loss);
        for (double rate : p.rates_hz) {
          const auto row = std::find_if(rows.begin(), rows.end(), [&](const DegradationRow& x) {
            return x.method == m && x.rate_hz == rate && x.noise_rms_deg == noise && x.loss_fraction == loss;
          });
          out += row == rows.end() || !std::isfinite((*row).*field) ? " — |" : fmt::format(" {:.3f} |", (*row).*field);
        }
        out += "\n";
      }
  };
  for (EventMethod m : p.methods) {
    table(m, "saccade event F1", &DegradationRow::saccade_f1);
    table(m, "pursuit sample κ", &DegradationRow::pursuit_kappa);
  }
  return out;
}

}  // namespace foveal
