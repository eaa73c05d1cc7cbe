// foveal/gaze/summary.cpp — recording summaries (JSON and text).
#include "foveal/gaze/summary.h"

#include <fmt/format.h>

#include <cmath>

namespace foveal {

std::vector<bool> causal_fixation_mask(const Recording& r, FixationMethod method, const FixationParams& params,
                                       const GazeGeometry& geometry) {
  FixationTracker tracker(method, params, geometry);
  std::vector<bool> mask(r.samples.size());
  for (size_t i = 0; i < r.samples.size(); ++i) {
    tracker.push(r.samples[i]);
    mask[i] = tracker.in_fixation();
  }
  return mask;
}

namespace {

nlohmann::json agreement_json(const Agreement& a) {
  return {{"samples", a.samples},
          {"agreement", a.agreement},
          {"kappa", a.kappa},
          {"filter_fixation_fraction", a.filter_fraction},
          {"tracker_fixation_fraction", a.reference_fraction}};
}

}  // namespace

GazeSummary summarize_recording(const Recording& r, const Display& display, const FixationParams& params) {
  const GazeGeometry geometry(display, r.screen_px);
  GazeSummary out;
  nlohmann::json fixations = nlohmann::json::object();
  for (FixationMethod m : {FixationMethod::ivt, FixationMethod::idt}) {
    FilterSummary f;
    f.method = m;
    f.result = m == FixationMethod::ivt ? detect_ivt(r, geometry, params) : detect_idt(r, geometry, params);
    const std::vector<bool> mask = fixation_mask(f.result);
    size_t valid = 0, fix = 0;
    for (size_t i = 0; i < mask.size(); ++i)
      if (r.samples[i].valid) {
        ++valid;
        fix += mask[i];
      }
    f.fixation_fraction = valid ? static_cast<double>(fix) / valid : 0;
    double total = 0;
    for (const Fixation& x : f.result.fixations) total += x.duration_s();
    f.mean_duration_ms = f.result.fixations.empty() ? 0 : 1000 * total / f.result.fixations.size();
    nlohmann::json j = {
        {"count", f.result.fixations.size()}, {"mean_duration_ms", f.mean_duration_ms}, {"fixation_fraction", f.fixation_fraction}};
    if (r.has_tracker_fixations) {
      f.agreement = agreement_with_events(r, mask, r.fixations);
      f.causal_agreement = agreement_with_events(r, causal_fixation_mask(r, m, params, geometry), r.fixations);
      j["agreement"] = f.agreement->agreement;
      j["kappa"] = f.agreement->kappa;
      j["comparison"] = agreement_json(*f.agreement);
      j["causal"] = agreement_json(*f.causal_agreement);
    }
    fixations[to_string(m)] = j;
    out.filters.push_back(std::move(f));
  }
  const nlohmann::json parameters = {{"ivt_threshold_deg_s", params.velocity_threshold_deg_s},
                                     {"velocity_window_ms", params.velocity_window_s * 1000},
                                     {"gap_fill_ms", params.gap_fill_s * 1000},
                                     {"merge_gap_ms", params.merge_gap_s * 1000},
                                     {"merge_angle_deg", params.merge_angle_deg},
                                     {"min_fixation_ms", params.min_fixation_s * 1000},
                                     {"idt_dispersion_deg", params.dispersion_deg},
                                     {"idt_min_duration_ms", params.min_duration_s * 1000}};
  const size_t valid = r.valid_count();
  out.json = {{"format", to_string(r.format)},
              {"source", r.source},
              {"tracker", r.tracker},
              {"eyes", r.eyes},
              {"samples", r.samples.size()},
              {"valid_samples", valid},
              {"valid_fraction", r.samples.empty() ? 0.0 : static_cast<double>(valid) / r.samples.size()},
              {"rate_hz", r.rate_hz()},
              {"nominal_rate_hz", r.nominal_rate_hz},
              {"duration_s", r.duration_s()},
              {"recorded_s", r.recorded_s()},
              {"blocks", std::max<size_t>(1, r.block_starts.size())},
              {"start_s", r.samples.empty() ? 0.0 : r.samples.front().t_s},
              {"screen_px", {r.screen_px.x, r.screen_px.y}},
              {"screen_from_file", r.screen_from_file},
              {"display", {{"width_cm", display.width_cm}, {"height_cm", display.height_cm}, {"distance_cm", display.distance_cm}}},
              {"pixels_per_degree", geometry.pixels_per_degree()},
              {"tracker_blinks", r.blinks.size()},
              {"fixations", fixations},
              {"fixation_parameters", parameters},
              {"tracker_fixations", r.has_tracker_fixations ? nlohmann::json(r.fixations.size()) : nlohmann::json()},
              {"notes", r.notes}};
  return out;
}

std::string format_summary(const Recording& r, const GazeSummary& s) {
  const auto& j = s.json;
  std::string out = fmt::format("foveal gaze: {} — {}, {}\n", r.source, r.tracker, r.eyes);
  out += fmt::format("  samples   {} ({:.1f}% valid), {:.1f} Hz{}, {:.2f} s", r.samples.size(), 100 * j["valid_fraction"].get<double>(),
                     r.rate_hz(), r.nominal_rate_hz > 0 ? fmt::format(" (file: {:g} Hz)", r.nominal_rate_hz) : "", r.duration_s());
  if (r.block_starts.size() > 1) out += fmt::format(" in {} blocks ({:.2f} s recorded)", r.block_starts.size(), r.recorded_s());
  out += "\n";
  out +=
      fmt::format("  screen    {}x{} px ({}), display {:g}x{:g} cm at {:g} cm: {:.1f} px/deg\n", r.screen_px.x, r.screen_px.y,
                  r.screen_from_file ? "from the file" : "assumed: --screen / --display", j["display"]["width_cm"].get<double>(),
                  j["display"]["height_cm"].get<double>(), j["display"]["distance_cm"].get<double>(), j["pixels_per_degree"].get<double>());
  if (r.has_tracker_fixations || !r.blinks.empty())
    out += fmt::format("  tracker   {} fixations, {} blinks\n", r.fixations.size(), r.blinks.size());
  out += fmt::format("  {:<8}  {:>9}  {:>9}  {:>6}", "filter", "fixations", "mean dur", "fix %");
  if (r.has_tracker_fixations) out += fmt::format("  {:>18}  {:>18}", "agreement (kappa)", "causal (kappa)");
  out += "\n";
  for (const FilterSummary& f : s.filters) {
    out += fmt::format("  {:<8}  {:>9}  {:>6.0f} ms  {:>5.1f}%", to_string(f.method), f.result.fixations.size(), f.mean_duration_ms,
                       100 * f.fixation_fraction);
    if (f.agreement)
      out += fmt::format("  {:>10.1f}% ({:.2f})  {:>10.1f}% ({:.2f})", 100 * f.agreement->agreement, f.agreement->kappa,
                         100 * f.causal_agreement->agreement, f.causal_agreement->kappa);
    out += "\n";
  }
  for (const std::string& note : r.notes) out += fmt::format("  note      {}\n", note);
  return out;
}

}  // namespace foveal
