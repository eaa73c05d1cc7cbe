// foveal bench latency: the three loops on a small recording under the model clock (the same
// figures twice), the JSON fields the docs name, errors in the command line's words.
#include "cli_helpers.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <string>

using namespace foveal_test;

namespace {

// 1.6 s at 500 Hz (or `hz`) on a 1680×1050 screen: a fixation, a 20° saccade (a smooth bell of
// velocity over 65 ms), a fixation, a saccade back, a fixation.
std::string write_saccades(const std::string& name, double hz = 500) {
  const fs::path path = scratch(name);
  fs::create_directories(path.parent_path());
  std::ofstream out(path);
  out << "t,x,y\n";
  auto x_at = [](double t) {
    auto bell = [](double tau) { return tau <= 0 ? 0.0 : tau >= 1 ? 1.0 : tau - std::sin(2 * M_PI * tau) / (2 * M_PI); };
    return 400 + 800 * bell((t - 0.4) / 0.065) - 800 * bell((t - 1.0) / 0.065);
  };
  for (int i = 0; i < 1.6 * hz; ++i) {
    const double t = i / hz;
    out << t << "," << x_at(t) + 0.3 * (i % 3) << "," << 520 + 0.2 * (i % 2) << "\n";
  }
  return path.string();
}

}  // namespace

TEST(BenchLatencyCli, ThreeLoopsUnderTheModelClockWriteTheDocumentedJson) {
  const std::string rec = write_saccades("saccades.csv");
  const std::string args = "bench latency --scene builtin:box --size 168x105 --max-rays 64 --recording " + rec +
                           " --duration 1.5 --clock model --model-rays-per-ms 2000 --model-fixed-ms 3 --min-amplitude 5";
  const CliRun a = foveal_test::foveal(args + " --json a.json --timeline a.png");
  ASSERT_EQ(a.status, 0) << a.err << a.out;
  EXPECT_NE(a.out.find("| deadline+prediction |"), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("× ray bound (model's rate)"), std::string::npos) << a.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("a.json")));
  ASSERT_EQ(j["recordings"].size(), 1u);
  EXPECT_EQ(j["periphery_share"].get<double>(), 1.0);  // the periphery runs to the deadline by default
  EXPECT_EQ(a.out.find("the periphery's rays within"), std::string::npos);
  const auto& r = j["recordings"][0];
  for (const char* loop : {"whole-frame", "deadline", "deadline+prediction"}) {
    SCOPED_TRACE(loop);
    const auto& l = r[loop];
    for (const char* key : {"budget_ms", "frames", "frames_late", "frame_ms_p50", "frame_ms_p99", "saccades"})
      EXPECT_TRUE(l.contains(key)) << key;
    EXPECT_NEAR(l["budget_ms"].get<double>(), 1000.0 / 60, 1e-9);
    ASSERT_EQ(l["saccades"].size(), 2u);  // the two 20° saccades
    for (const auto& s : l["saccades"]) {
      EXPECT_NEAR(s["amplitude_deg"].get<double>(), 20, 4);
      for (const char* key : {"landing_s", "landing_to_converged_ms", "ray_bound_ms", "fixation_ms"}) EXPECT_TRUE(s.contains(key)) << key;
      EXPECT_GT(s["ray_bound_ms"].get<double>(), 0);
      // The model clock's bound: the same rays at the model's 2000 rays/ms
      EXPECT_NEAR(s["model_ray_bound_ms"].get<double>(), s["ray_bound_ms"].get<double>() * r["raw_rays_per_ms"].get<double>() / 2000, 1e-6);
      // the eye stays ~0.53 s: until the saccade back, and after it until the recording ends
      EXPECT_NEAR(s["fixation_ms"].get<double>(), 534, 40);
    }
  }
  // The eye returns to where it looked first, a fovea the deadline loops converged then: the frame
  // on screen when it lands already shows it (0 ms, not the wait for the next refresh)
  for (const char* loop : {"deadline", "deadline+prediction"})
    EXPECT_EQ(r[loop]["saccades"][1]["landing_to_converged_ms"].get<double>(), 0.0) << loop;
  // The deadline loops make a frame every refresh and never miss one under the model clock
  EXPECT_EQ(r["deadline"]["frames_late"], 0);
  EXPECT_GE(r["deadline"]["frames"].get<int>(), 89);
  EXPECT_LE(r["deadline"]["frame_ms_p99"].get<double>(), 1000.0 / 60);
  // Where late frames' pauses fell: listed for the deadline loops (none here), not the whole-frame one
  EXPECT_EQ(r["deadline"]["late_frames"], nlohmann::json::array());
  EXPECT_FALSE(r["whole-frame"].contains("late_frames"));
  EXPECT_TRUE(fs::exists(scratch("a.png")));
  // What else ran on the machine meanwhile (Linux): shares of all CPUs' time
  if (j.contains("machine")) {
    for (const char* key : {"others_cpu_fraction", "steal_fraction"}) {
      EXPECT_GE(j["machine"][key].get<double>(), 0.0) << key;
      EXPECT_LE(j["machine"][key].get<double>(), 1.0) << key;
    }
    EXPECT_NE(a.out.find("The machine during the run: other processes kept"), std::string::npos) << a.out;
    // … and by name, the busiest first (this process not among them)
    ASSERT_TRUE(j["machine"]["others"].is_array());
    double before = INFINITY;
    for (const auto& o : j["machine"]["others"]) {
      EXPECT_LE(o["cpu_ms"].get<double>(), before);
      before = o["cpu_ms"].get<double>();
      EXPECT_TRUE(o["name"].is_string() && o["kernel"].is_boolean() && o["slices"].is_number() && o["pid"].is_number());
    }
    if (!j["machine"]["others"].empty()) EXPECT_NE(a.out.find("What else ran, the busiest first: "), std::string::npos) << a.out;
    // The kernel's tick in the JSON; its sentence against the margin only on the wall clock (no frame here waits for a core)
    ASSERT_TRUE(j["machine"]["kernel"].is_object());
    EXPECT_TRUE(j["machine"]["kernel"]["release"].is_string());
    EXPECT_EQ(a.out.find("ticks at"), std::string::npos) << a.out;
  }
#if defined(__linux__)
  EXPECT_TRUE(j.contains("machine"));
#endif
  // A given cost model: the deadline loops' figures are the same on a second run (but the ray
  // bound, whose raw rate is measured, and the whole-frame loop, whose frames' cost is)
  const CliRun b = foveal_test::foveal(args + " --json b.json --loops deadline,deadline+prediction");
  ASSERT_EQ(b.status, 0) << b.err;
  const auto k = nlohmann::json::parse(std::ifstream(scratch("b.json")));
  EXPECT_FALSE(k["recordings"][0].contains("whole-frame"));
  auto without_bound = [](nlohmann::json saccades) {
    for (auto& s : saccades) s.erase("ray_bound_ms");
    return saccades;
  };
  // What prediction gains in the median over the loop without it, beside a third of the median saccade
  ASSERT_TRUE(r.contains("prediction_gain_ms"));
  EXPECT_DOUBLE_EQ(r["prediction_gain_ms"].get<double>(), r["deadline"]["median_landing_to_converged_ms"].get<double>() -
                                                              r["deadline+prediction"]["median_landing_to_converged_ms"].get<double>());
  EXPECT_NEAR(r["third_of_median_saccade_ms"].get<double>(), r["deadline"]["saccades"][0]["duration_ms"].get<double>() / 3, 10);
  EXPECT_NE(a.out.find("Gained over the deadline loop's median: deadline+prediction"), std::string::npos) << a.out;
  EXPECT_FALSE(r.contains("prediction_note"));  // 500 Hz: nothing to say
  for (const char* loop : {"deadline", "deadline+prediction"}) {
    EXPECT_EQ(without_bound(k["recordings"][0][loop]["saccades"]), without_bound(r[loop]["saccades"])) << loop;
    EXPECT_EQ(k["recordings"][0][loop]["timeline"], r[loop]["timeline"]) << loop;
  }
}

// The perfect predictor the bench offers as a yardstick: from each detected flight on, the fovea at
// the saccade's true landing (prediction error 0 where the prediction loop's is not)
TEST(BenchLatencyCli, TheOracleLoopPlacesTheFoveaAtTheTrueLanding) {
  const std::string rec = write_saccades("saccades-oracle.csv");
  const CliRun r = foveal_test::foveal("bench latency --scene builtin:box --size 168x105 --max-rays 64 --recording " + rec +
                                       " --duration 1.5 --clock model --model-rays-per-ms 2000 --model-fixed-ms 3 --min-amplitude 5"
                                       " --loops deadline+prediction,deadline+oracle --json oracle.json");
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("| deadline+oracle |"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("oracle.json")));
  const auto& rec_json = j["recordings"][0];
  ASSERT_EQ(rec_json["deadline+oracle"]["saccades"].size(), 2u);
  for (const auto& s : rec_json["deadline+oracle"]["saccades"]) {
    ASSERT_TRUE(s.contains("predicted_error_deg"));
    EXPECT_LT(s["predicted_error_deg"].get<double>(), 1e-6);
  }
  // What each gains over the loop without prediction, beside a third of the median saccade (65 ms here)
  EXPECT_FALSE(rec_json.contains("prediction_gain_ms"));  // (no deadline loop ran)
  double predicted = 0;                                   // the mirror's last prediction before each landing is not exact
  for (const auto& s : rec_json["deadline+prediction"]["saccades"]) predicted += s["predicted_error_deg"].get<double>();
  EXPECT_GT(predicted, 1e-3);
}

// A 60-Hz tracker: a saccade spans a few samples and its landing is known too late to gain much,
// which the report says beside the gain (Landing.UnderNinetyHertzALandingIsKnownTooLate)
TEST(BenchLatencyCli, ASlowTrackersPredictionIsSaidToGainLittle) {
  const std::string rec = write_saccades("saccades60.csv", 60);
  const CliRun run = foveal_test::foveal("bench latency --scene builtin:box --size 64x40 --max-rays 16 --recording " + rec +
                                         " --duration 1.5 --clock model --model-rays-per-ms 500 --model-fixed-ms 3 --min-amplitude 5"
                                         " --loops deadline,deadline+prediction --json slow.json");
  ASSERT_EQ(run.status, 0) << run.err << run.out;
  EXPECT_NE(run.out.find("Prediction: gaze samples come 16.7 ms apart (60 Hz)"), std::string::npos) << run.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("slow.json")));
  EXPECT_NE(j["recordings"][0]["prediction_note"].get<std::string>().find("too late to gain much"), std::string::npos);
}

TEST(BenchLatencyCli, BadOptionsAreOneClearLine) {
  const std::string rec = write_saccades("saccades2.csv");
  const std::string base = "bench latency --scene builtin:box --size 64x40 --recording " + rec;
  expect_one_line_error(base + " --loops bogus", "--loops");
  expect_one_line_error(base + " --loops deadline,whole-frame,deadline", "--loops: 'deadline' given twice");  // one figure per name
  expect_one_line_error(base + " --start 99", "--start");
  EXPECT_EQ(foveal_test::foveal(base + " --start 99").out.find("references"), std::string::npos);  // refused before any tracing
  expect_one_line_error(base + " --clock sundial", "--clock");
  expect_one_line_error(base + " --frame-budget-ms -3", "--frame-budget-ms");
  expect_one_line_error(base + " --latency-ms -1", "--latency-ms");
  expect_one_line_error(base + " --margin-ms 20", "--margin-ms");
  expect_one_line_error(base + " --periphery-share 0", "--periphery-share: must be in (0, 1]");
  expect_one_line_error(base + " --periphery-share 1.5", "--periphery-share: must be in (0, 1]");
  expect_one_line_error(base + " --min-scale 0", "--min-scale: must be in (0, 1]");
  expect_one_line_error(base + " --max-rays 0", "--max-rays: bench latency judges the fovea's AO");
  expect_one_line_error(base + " --model-rays-per-ms 100 --model-fixed-ms 1", "--model-rays-per-ms");
  expect_one_line_error("bench latency --scene builtin:box --recording /no/such/recording.asc", "/no/such/recording.asc");
  // A recording it cannot replay is named before any tracing: one sample, or times in milliseconds
  std::ofstream(scratch("one-sample.csv")) << "t,x,y\n0,10,10\n";
  expect_one_line_error("bench latency --scene builtin:box --size 64x40 --recording one-sample.csv",
                        "one-sample.csv: 1 sample at one time: bench latency replays a recording over time");
  {
    std::ofstream ms(scratch("milliseconds.csv"));
    ms << "t,x,y\n";
    for (int i = 0; i < 2000; i += 2) ms << i << ",100,100\n";  // 500 Hz in milliseconds
  }
  const CliRun in_ms = foveal_test::foveal("bench latency --scene builtin:box --size 64x40 --recording milliseconds.csv");
  EXPECT_EQ(in_ms.status, 1);
  EXPECT_NE(in_ms.err.find("milliseconds.csv: its samples come 2 s apart: under 20 Hz no saccade is seen"), std::string::npos) << in_ms.err;
  EXPECT_NE(in_ms.err.find("are the times in milliseconds? bench latency takes seconds"), std::string::npos) << in_ms.err;
  EXPECT_EQ(in_ms.out.find("references"), std::string::npos);
  // The landing predictor's parameters, each named (not renamed into another option's words)
  expect_one_line_error(base + " --landing speed=3", "--landing: speed: no parameter of the landing predictor");
  expect_one_line_error(base + " --landing skew=9", "--landing: skew: must be in [0.25, 4]");
  expect_one_line_error(base + " --landing onset_deg_s", "--landing: 'onset_deg_s': expected NAME=VALUE");
  expect_one_line_error(base + " --landing min_flight_deg=-1", "--landing: min_flight_deg: must be >= 0");
  expect_one_line_error("replay --scene builtin:box --size 64x40 -o out --gaze " + rec + " --landing skew=2",
                        "--landing: needs --realtime");
}

// A budget shorter than the default margin (2 ms) runs, keeping a quarter of it free instead; a
// margin given outright must fit in the budget.
TEST(BenchLatencyCli, AShortBudgetKeepsAQuarterOfItByDefault) {
  const std::string rec = write_saccades("saccades3.csv");
  const std::string base = "bench latency --scene builtin:box --size 64x40 --duration 0.2 --loops deadline --recording " + rec;
  const CliRun r = foveal_test::foveal(base + " --frame-budget-ms 1 --json short.json");
  EXPECT_EQ(r.status, 0) << r.err;
  expect_one_line_error(base + " --frame-budget-ms 1 --margin-ms 1", "--margin-ms");
  // The JSON keeps the margin the wall clock's loops kept: a quarter of the short budget, or as given;
  // the model clock keeps none
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(scratch("short.json")))["margin_ms"].get<double>(), 0.25);
  ASSERT_EQ(foveal_test::foveal(base + " --margin-ms 3 --json given.json").status, 0);
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(scratch("given.json")))["margin_ms"].get<double>(), 3.0);
  ASSERT_EQ(foveal_test::foveal(base + " --clock model --model-rays-per-ms 2000 --model-fixed-ms 3 --json model.json").status, 0);
  EXPECT_TRUE(nlohmann::json::parse(std::ifstream(scratch("model.json")))["margin_ms"].is_null());
}

// --periphery-share: the deadline loops' periphery stops at that share of each budget. Under the
// model clock no frame of the periphery alone costs more than the share; the run says so and keeps it.
TEST(BenchLatencyCli, ThePeripherysShareIsTheLoopsAndIsKept) {
  const std::string rec = write_saccades("saccades4.csv");
  const std::string base = "bench latency --scene builtin:box --size 168x105 --max-rays 64 --recording " + rec +
                           " --duration 1.5 --clock model --model-rays-per-ms 2000 --model-fixed-ms 3 --min-amplitude 5 --loops deadline";
  struct Run {
    nlohmann::json json;
    std::vector<double> costs;  // each deadline frame's, ms
    std::string out;
  };
  auto run = [&](const std::string& extra, const std::string& json) {
    const CliRun r = foveal_test::foveal(base + extra + " --json " + json);
    EXPECT_EQ(r.status, 0) << r.err;
    Run got{nlohmann::json::parse(std::ifstream(scratch(json))), {}, r.out};
    for (const auto& f : got.json["recordings"][0]["deadline"]["timeline"]) got.costs.push_back(f["cost_ms"].get<double>());
    return got;
  };
  const Run half = run(" --periphery-share 0.5", "half.json");
  const Run whole = run("", "whole.json");
  EXPECT_EQ(half.json["periphery_share"].get<double>(), 0.5);
  const double budget = 1000.0 / 60;
  // Frames between 0.5 and the whole budget are the fovea's: fewer at 0.5, where the periphery stops at half
  auto between = [&](const std::vector<double>& c) {
    return std::count_if(c.begin(), c.end(), [&](double ms) { return ms > 0.5 * budget + 1e-3 && ms <= budget; });
  };
  EXPECT_LT(between(half.costs), between(whole.costs));
  EXPECT_GT(std::count_if(half.costs.begin(), half.costs.end(), [&](double ms) { return std::abs(ms - 0.5 * budget) < 1e-3; }), 0);
  EXPECT_NE(half.out.find("the periphery's rays within 50 % of each budget"), std::string::npos) << half.out;
  EXPECT_EQ(whole.out.find("the periphery's rays within"), std::string::npos);
}
