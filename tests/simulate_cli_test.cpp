// `foveal simulate` and `foveal bench vision` as a user runs them.
#include "cli_helpers.h"
#include "fake_pupil.h"

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

TEST(SimulateCli, RecordedFixationsDriveTheSteps) {
  const std::string rec = write_three_fixations("blink.csv", true);
  const std::string common = "simulate --gaze " + rec + " --screen 480x300 --size 160x100 --save-steps '' ";
  for (const char* filter : {"ivt", "idt"}) {
    const CliRun r = foveal_test::foveal(common + "--fixation " + filter + " -o gz --stats gz.json");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("3 fixations"), std::string::npos) << r.out;
    const auto j = nlohmann::json::parse(std::ifstream(scratch("gz.json")));
    ASSERT_EQ(j["steps"].size(), 3u) << filter;  // every fixation, as --steps was not given
    // The fixations on the 480×300 screen, in the 160×100 render
    const double expected[3][2] = {{100 / 3.0, 100 / 3.0}, {400 / 3.0, 200 / 3.0}, {80, 50}};
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(j["steps"][k]["focus_px"][0].get<double>(), expected[k][0], 0.3) << filter << " step " << k + 1;
      EXPECT_NEAR(j["steps"][k]["focus_px"][1].get<double>(), expected[k][1], 0.3) << filter << " step " << k + 1;
      EXPECT_EQ(j["steps"][k]["blink"].get<bool>(), k == 2) << filter << " step " << k + 1;
      EXPECT_GT(j["steps"][k]["gaze"]["duration_s"].get<double>(), 0.2);
    }
  }
  // The blink made the field forget: without it, the third step remembers more sharp surface
  ASSERT_EQ(foveal_test::foveal(common + "--no-gaze-blinks -o gz2 --stats gz2.json -q").status, 0);
  const auto blink = nlohmann::json::parse(std::ifstream(scratch("gz.json")));
  const auto no_blink = nlohmann::json::parse(std::ifstream(scratch("gz2.json")));
  EXPECT_FALSE(no_blink["steps"][2]["blink"].get<bool>());
  EXPECT_LT(blink["steps"][2]["sharp_fraction"].get<double>(), no_blink["steps"][2]["sharp_fraction"].get<double>());
  // --steps caps the fixations used
  ASSERT_EQ(foveal_test::foveal(common + "--steps 2 -o gz3 --stats gz3.json -q").status, 0);
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(scratch("gz3.json")))["steps"].size(), 2u);
  // What cannot drive the steps says why, in one line
  for (const auto& [args, expected] :
       std::vector<std::pair<std::string, std::string>>{{"--fixation mean", "'mean' gives a gaze point per frame"},
                                                        {"--fixation tracker", "no fixation events of its tracker"},
                                                        {"--start 5", "no fixations after --start 5 s"}})
    expect_one_line_error(common + args + " -o gz4", expected);
}

TEST(SimulateCli, LiveTrackerDrivesTheStepsAndItsHangUpIsOneLine) {
  FakePupil fake;
  std::vector<std::pair<std::string, std::string>> messages;
  for (int i = 0; i < 60; ++i) messages.emplace_back("surfaces.screen", surface_gaze(0.25, 0.75, true, 10 + 0.004 * i));
  for (int i = 0; i < 60; ++i) messages.emplace_back("surfaces.screen", surface_gaze(0.75, 0.25, true, 10.3 + 0.004 * i));
  fake.serve(messages, true, nullptr);
  const CliRun r = foveal_test::foveal("simulate --gaze '" + fake.url("surface=screen") +
                                       "' --screen 400x200 --size 40x20 --steps 5 "
                                       "--live-timeout 2 --save-steps '' -o live --stats live.json");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("stopped after 2 steps"), std::string::npos) << r.err;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("live.json")));
  ASSERT_EQ(j["steps"].size(), 2u);
  // norm (0.25, 0.75) of 400×200 (origin bottom-left) → (100, 50) → render ÷10; then (30, 15)
  EXPECT_NEAR(j["steps"][0]["focus_px"][0].get<double>(), 10.0, 1e-3);
  EXPECT_NEAR(j["steps"][0]["focus_px"][1].get<double>(), 5.0, 1e-3);
  EXPECT_NEAR(j["steps"][1]["focus_px"][0].get<double>(), 30.0, 1e-3);
  EXPECT_NEAR(j["steps"][1]["focus_px"][1].get<double>(), 15.0, 1e-3);
  EXPECT_TRUE(fs::exists(scratch("live/perceived.png")));
}

TEST(SimulateCli, BenchVisionReportsEveryStage) {
  const CliRun r = foveal_test::foveal("bench vision --scene builtin:plane --size 64x40 --steps 3 --json bv.json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("bv.json")));
  ASSERT_EQ(j["rows"].size(), 1u);
  EXPECT_EQ(j["rows"][0]["steps"], 2);
  EXPECT_GT(j["rows"][0]["time_ms"]["total"].get<double>(), 0);
}

TEST(SimulateCli, ImpairedEyesAreAppliedAndTimed) {
  const CliRun r = foveal_test::foveal(
      "simulate --size 160x100 --steps 3 --eye age:70+cataract:0.5+achromatopsia+field:arcuate:20 "
      "-o sim-impaired --stats impaired.json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("impaired glare (age 70, cataract 0.5)"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("impaired.json")));
  EXPECT_NE(j["impairments"].get<std::string>().find("field loss"), std::string::npos);
  EXPECT_GT(j["time_ms"]["impairments"].get<double>(), 0.0);
  EXPECT_GT(j["time_ms"]["media"].get<double>(), 0.0);
  EXPECT_GT(j["time_ms"]["retina"].get<double>(), 0.0);
  EXPECT_GT(j["time_ms"]["colour"].get<double>(), 0.0);
}

TEST(SimulateCli, BadInputGivesOneClearLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"simulate -o s --eye blind", "unknown preset 'blind'"},
      {"simulate -o s --eye glaucoma:3", "glaucoma severity"},
      {"simulate -o s --pupil 0", "--pupil"},
      {"simulate -o s --save-steps 0", "--save-steps"},
      {"simulate -o s --size 4x4", "--size"},
      {"simulate -o s --size 7x8", "--size"},
      {"simulate -o s --fov 0", "--fov"},
      {"simulate -o s --fov 180", "--fov"},
      {"simulate -o s --steps 0", "--steps"},
      {"simulate -o s --steps 100001", "--steps"},
      {"simulate -o s --fast-threshold 0", "--fast-threshold"},
      {"simulate -o s --fast-threshold 256", "--fast-threshold"},
      {"simulate -o s --blink-every -1", "--blink-every"},
      {"simulate -o s --saccade-max 0", "--saccade-max"},
      {"simulate -o s --saccade-min -1", "--saccade-min"},
      {"simulate -o s --eye glaucoma:-0.1", "glaucoma severity"},
      {"simulate -o s --eye cataract:-0.01", "severity must be in [0, 1]"},
      {"simulate -o s --voxel -1", "--voxel"},
      {"simulate -o s --from 0,0,1", "--from and --look"},
      {"simulate --steps 2", "--output"},
      {"simulate -o s --gaze nowhere.asc", "nowhere.asc"},
      {"simulate -o s --gaze tcp://host:1", "unknown live source"},
      {"simulate -o s --gaze pupil://127.0.0.1:1 --fixation tracker", "fixation events"},
      {"simulate -o s --stimulus 0,0,10,10", "--stimulus requires --gaze"},
      {"simulate -o s --eye field:missing-field.csv", "missing-field.csv"},
      {"simulate -o s --eye cataract:1.5", "severity must be in [0, 1]"},
      {"simulate -o s --eye field:hemianopia:up", "not one of the allowed sides"},
  };
  for (const auto& [args, expected] : cases) {
    const CliRun r = foveal_test::foveal(args);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_EQ(lines(r.err), 1u) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
  }
}
