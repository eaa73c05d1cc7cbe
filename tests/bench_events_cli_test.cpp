// foveal bench events: the event detectors under known noise and loss, from the command line.
#include "cli_helpers.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <string>
#include <utility>
#include <vector>

using namespace foveal_test;

// foveal bench events: the degradation study in small, with its JSON, and bad options.
TEST(BenchEventsCli, DegradationRowsAndBadOptions) {
  const CliRun r = foveal_test::foveal("bench events --seconds 20 --rates 500 --noise 0.1 --loss 0.1 --methods auto,nhp --json ev.json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("nhr — saccade event F1"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("ev.json")));
  ASSERT_EQ(j["rows"].size(), 2u);
  EXPECT_EQ(j["rows"][0]["detector"], "nhr");
  EXPECT_GE(j["rows"][0]["saccade_f1"].get<double>(), 0.9);
  EXPECT_GT(j["rows"][0]["true_saccades"].get<int>(), 20);
  for (const auto& [args, word] : std::vector<std::pair<std::string, std::string>>{{"--rates 500,x", "--rates: 'x' is not a number"},
                                                                                   {"--loss 0.9", "loss_fractions"},
                                                                                   {"--methods hmm", "unknown detector 'hmm'"},
                                                                                   {"--seconds 0", "seconds"}}) {
    const CliRun bad = foveal_test::foveal("bench events --seconds 5 " + args);
    EXPECT_NE(bad.status, 0) << args;
    EXPECT_NE(bad.err.find(word), std::string::npos) << args << ": " << bad.err;
  }
}
