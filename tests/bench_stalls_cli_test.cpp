// foveal bench stalls: the table and the JSON the docs name, and bad options as one clear line.
#include "cli_helpers.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <string>

using namespace foveal_test;

TEST(BenchStallsCli, AShortProbeWritesTheDocumentedFigures) {
  const CliRun a = foveal_test::foveal("bench stalls --duration 0.5 --threads 2 --json s.json --markdown s.md");
  ASSERT_EQ(a.status, 0) << a.err << a.out;
  EXPECT_NE(a.out.find("| off the CPU:"), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("| on the CPU:"), std::string::npos) << a.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("s.json")));
  EXPECT_EQ(j["threads"], 2);
  EXPECT_GE(j["duration_s"].get<double>(), 0.45);
  EXPECT_GT(j["chunks"].get<long>(), 100);
  EXPECT_GT(j["chunk_us"].get<double>(), 10);
  EXPECT_EQ(j["margin_ms"].get<double>(), 2.0);  // the loop's own margin by default
  int listed = 0;
  for (const char* kind : {"off_cpu", "on_cpu"}) {
    for (const char* key : {"count", "per_minute", "worst_ms", "beyond_margin"}) EXPECT_TRUE(j[kind].contains(key)) << kind << key;
    listed += j[kind]["count"].get<int>();
  }
  // Every stall is listed, of the kind its clocks say, and no shorter than the threshold
  ASSERT_EQ(static_cast<int>(j["stalls"].size()), listed);
  for (const auto& s : j["stalls"]) {
    EXPECT_GE(s["wall_ms"].get<double>(), 1.0);
    EXPECT_EQ(s["on_cpu"].get<bool>(), s["cpu_ms"].get<double>() >= 0.5 * s["wall_ms"].get<double>());
  }
  // What else ran meanwhile, by name, the busiest first
  ASSERT_TRUE(j["others"].is_array());
  EXPECT_LE(j["others"].size(), 5u);
  for (size_t k = 1; k < j["others"].size(); ++k)
    EXPECT_LE(j["others"][k]["cpu_ms"].get<double>(), j["others"][k - 1]["cpu_ms"].get<double>());
  if (!j["others"].empty()) EXPECT_NE(a.out.find("What else ran on this machine meanwhile"), std::string::npos) << a.out;
  // The kernel's tick where its config states it, and then the sentence on it against the margin
  ASSERT_TRUE(j["kernel"].is_object());
  for (const char* key : {"release", "hz", "preempt", "source"}) EXPECT_TRUE(j["kernel"].contains(key)) << key;
  if (j["kernel"]["hz"].is_number()) {
    const int hz = j["kernel"]["hz"].get<int>();
    EXPECT_NE(a.out.find(fmt::format("ticks at {} Hz", hz)), std::string::npos) << a.out;
    EXPECT_NE(a.out.find(fmt::format("up to {:.1f} ms, {} the 2 ms margin", 1000.0 / hz, 1000.0 / hz > 2 ? "longer than" : "within")),
              std::string::npos)
        << a.out;
  } else {
    EXPECT_EQ(a.out.find("ticks at"), std::string::npos) << a.out;
  }
  std::ifstream md(scratch("s.md"));
  EXPECT_TRUE(md.good());
}

TEST(BenchStallsCli, BadOptionsAreOneClearLine) {
  expect_one_line_error("bench stalls --duration 0", "--duration");
  expect_one_line_error("bench stalls --duration 0.1 --chunk-us 1", "--chunk-us");
  expect_one_line_error("bench stalls --duration 0.1 --threshold-ms 0.05", "--threshold-ms");
  expect_one_line_error("bench stalls --duration 0.1 --margin-ms -1", "--margin-ms");
  const CliRun r = foveal_test::foveal("bench stalls --threads -2");  // refused by the option's own check
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("--threads"), std::string::npos) << r.err;
}
