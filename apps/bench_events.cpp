// apps/bench_events.cpp — `foveal bench events`: the event detectors under known noise and loss.
#include "commands.h"
#include "foveal/experiments/event_degradation.h"
#include "foveal/render/outputs.h"
#include "foveal/util/error.h"
#include "foveal/util/text.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <memory>

namespace foveal::app {

namespace {

struct BenchEventsOptions {
  double seconds = 60;
  std::string rates = "250,500,1000,2000", noise = "0.02,0.05,0.1,0.2,0.3", loss = "0,0.05,0.1,0.15", methods = "nhr,nhp";
  double burst_ms = 10;
  unsigned seed = 11;
  std::string json, markdown;
};

std::vector<double> numbers(const std::string& text, const char* option) {
  std::vector<double> out;
  for (const std::string_view part : text::split(text, ',')) {
    const auto v = text::to_number(part);
    if (!v) fail("{}: '{}' is not a number", option, text::trim(part));
    out.push_back(*v);
  }
  return out;
}

int run_bench_events(const BenchEventsOptions& o) {
  DegradationParams p;
  p.seconds = o.seconds;
  p.rates_hz = numbers(o.rates, "--rates");
  p.noise_rms_deg = numbers(o.noise, "--noise");
  p.loss_fractions = numbers(o.loss, "--loss");
  if (!(o.burst_ms > 0)) fail("--burst-ms: {} is not positive", o.burst_ms);
  p.burst_s = o.burst_ms / 1000;
  p.seed = o.seed;
  p.methods.clear();
  for (const std::string_view m : text::split(o.methods, ',')) p.methods.push_back(parse_event_method(std::string(text::trim(m))));
  validate(p);
  fmt::print("foveal bench events: {} s of synthetic free viewing with pursuit per rate, {} conditions × {} detectors\n", p.seconds,
             p.rates_hz.size() * p.noise_rms_deg.size() * p.loss_fractions.size(), p.methods.size());
  const std::vector<DegradationRow> rows = run_event_degradation(p);
  const std::string table = degradation_markdown(p, rows);
  fmt::print("{}", table);
  if (!o.markdown.empty()) write_text_file(o.markdown, table);
  if (!o.json.empty()) {
    nlohmann::json list = nlohmann::json::array();
    auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    for (const DegradationRow& r : rows)
      list.push_back({{"rate_hz", r.rate_hz},
                      {"noise_rms_deg", r.noise_rms_deg},
                      {"loss_fraction", r.loss_fraction},
                      {"detector", to_string(r.method)},
                      {"saccade_f1", number(r.saccade_f1)},
                      {"saccade_kappa", number(r.saccade_kappa)},
                      {"pso_kappa", number(r.pso_kappa)},
                      {"fixation_kappa", number(r.fixation_kappa)},
                      {"pursuit_kappa", number(r.pursuit_kappa)},
                      {"pursuit_f1", number(r.pursuit_f1)},
                      {"samples", r.samples},
                      {"true_saccades", r.saccades}});
    write_text_file(o.json, nlohmann::json{{"seconds", p.seconds}, {"seed", p.seed}, {"burst_s", p.burst_s}, {"rows", list}}.dump(1));
  }
  return 0;
}

}  // namespace

std::function<int()> add_bench_events_command(CLI::App& bench) {
  auto* cmd = bench.add_subcommand(
      "events",
      "event detectors under known degradation: synthetic free viewing with pursuit (known events) at several sampling rates, "
      "white noise and bursts of lost samples, scored against the truth (saccade event F1, pursuit kappa)");
  auto o = std::make_shared<BenchEventsOptions>();
  cmd->add_option("--seconds", o->seconds, "synthetic recording length per rate, s")->capture_default_str();
  cmd->add_option("--rates", o->rates, "sampling rates, Hz, comma-separated")->capture_default_str();
  cmd->add_option("--noise", o->noise, "white noise, 2-D RMS in degrees, comma-separated")->capture_default_str();
  cmd->add_option("--loss", o->loss, "fractions of samples lost in bursts, comma-separated")->capture_default_str();
  cmd->add_option("--burst-ms", o->burst_ms, "mean length of a lost burst (each 0.5-1.5x this), ms")->capture_default_str();
  cmd->add_option("--methods", o->methods, "detectors, comma-separated (auto, nhr, nhp, nh, ek, ivt, idt, ivvt)")->capture_default_str();
  cmd->add_option("--seed", o->seed, "seed of the synthetic signal and its degradation")->capture_default_str();
  cmd->add_option("--json", o->json, "write every row as JSON")->check(output_file());
  cmd->add_option("--markdown", o->markdown, "write the tables as Markdown")->check(output_file());
  return [o] { return run_bench_events(*o); };
}

}  // namespace foveal::app
