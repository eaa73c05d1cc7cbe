// `foveal simulate` and `foveal bench vision` as a user runs them.
#include "cli_helpers.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

using namespace foveal_test;
namespace fs = std::filesystem;

TEST(SimulateCli, StepsStatsAndPictures) {
  const CliRun r = foveal_test::foveal("simulate --size 160x100 --steps 6 --save-steps 1,4 --blink-every 5 -o sim --stats sim.json");
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* f : {"sim/step_0001.png", "sim/step_0004.png", "sim/perceived.png", "sim/sharp.png", "sim/scanpath.png"})
    EXPECT_GT(fs::file_size(scratch(f)), 100u) << f;
  EXPECT_FALSE(fs::exists(scratch("sim/step_0002.png")));
  const auto j = nlohmann::json::parse(std::ifstream(scratch("sim.json")));
  for (const char* k : {"trace", "features", "sharpness", "blur", "total"}) EXPECT_GE(j["time_ms"][k].get<double>(), 0) << k;
  ASSERT_EQ(j["steps"].size(), 6u);
  for (const auto& s : j["steps"]) {
    EXPECT_EQ(s["focus_px"].size(), 2u);
    EXPECT_TRUE(s.contains("focus_depth_m"));
    EXPECT_GE(s["sharp_fraction"].get<double>(), 0.0);
    EXPECT_LE(s["sharp_fraction"].get<double>(), 1.0);
  }
  EXPECT_TRUE(j["steps"][5]["blink"].get<bool>());  // step 6 follows the 5-step blink interval
  EXPECT_FALSE(j["steps"][4]["blink"].get<bool>());
  // The same seed, the same fixations
  ASSERT_EQ(foveal_test::foveal("simulate --size 160x100 --steps 6 --blink-every 5 -o sim2 --stats sim2.json -q").status, 0);
  const auto j2 = nlohmann::json::parse(std::ifstream(scratch("sim2.json")));
  for (size_t k = 0; k < 6; ++k) EXPECT_EQ(j2["steps"][k]["focus_px"], j["steps"][k]["focus_px"]);
}

TEST(SimulateCli, BenchVisionReportsEveryStage) {
  const CliRun r = foveal_test::foveal("bench vision --scene builtin:plane --size 64x40 --steps 3 --json bv.json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("bv.json")));
  ASSERT_EQ(j["rows"].size(), 1u);
  EXPECT_EQ(j["rows"][0]["steps"], 2);
  EXPECT_GT(j["rows"][0]["time_ms"]["total"].get<double>(), 0);
}

TEST(SimulateCli, BadInputGivesOneClearLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"simulate -o s --eye blind", "unknown preset 'blind'"},
      {"simulate -o s --eye glaucoma:3", "glaucoma severity"},
      {"simulate -o s --pupil 0", "--pupil"},
      {"simulate -o s --save-steps 0", "--save-steps"},
      {"simulate -o s --size 4x4", "--size"},
      {"simulate -o s --voxel -1", "--voxel"},
      {"simulate -o s --from 0,0,1", "--from and --look"},
      {"simulate --steps 2", "--output"},
  };
  for (const auto& [args, expected] : cases) {
    const CliRun r = foveal_test::foveal(args);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_EQ(lines(r.err), 1u) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
  }
}
