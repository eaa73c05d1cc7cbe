// `--device` as a user meets it: cpu always, cuda only where a GPU answers, and the device named.
#include "cli_helpers.h"
#include "foveal/cuda/gpu.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace foveal_test {
namespace {

TEST(DeviceCli, CpuRunsAndTheChoiceIsPrinted) {
  const CliRun r = foveal_test::foveal("render --scene builtin:box --size 80x50 --max-rays 8 --device cpu --stats dev.json -o dev.png");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("device   cpu"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("dev.json")));
  EXPECT_EQ(j["device"], "cpu");
  // auto picks what is there and says so
  const CliRun a = foveal_test::foveal("render --scene builtin:box --size 80x50 --max-rays 8 -o dev_auto.png");
  ASSERT_EQ(a.status, 0) << a.err;
  EXPECT_NE(a.out.find(foveal::availability().usable ? "device   cuda (" : "device   cpu (no GPU: "), std::string::npos) << a.out;
}

TEST(DeviceCli, UnknownOrUnavailableDeviceIsOneLine) {
  expect_one_line_error("render --scene builtin:box --device opencl", "--device: unknown device 'opencl' (known: auto, cpu, cuda)");
  expect_one_line_error("bench ao --scene builtin:box --device tpu", "--device: unknown device 'tpu'");
  if (foveal::availability().usable) GTEST_SKIP() << "a GPU is usable here: --device cuda is not refused";
  expect_one_line_error("render --scene builtin:box --device cuda", "--device cuda: unavailable: " + foveal::availability().reason);
  expect_one_line_error("bench ao --scene builtin:box --device cuda", "--device cuda: unavailable");
  const std::string recording = write_three_fixations("device_three.csv");
  expect_one_line_error(
      "replay --gaze " + recording + " --screen 480x300 --scene builtin:box --size 48x30 --frames 2 -o dev_replay --device cuda",
      "--device cuda: unavailable");
  expect_one_line_error("simulate --scene builtin:box --size 64x48 --steps 2 -o dev_sim --device cuda", "--device cuda: unavailable");
  expect_one_line_error("bench vision --scene builtin:box --size 64x48 --steps 2 --device cuda", "--device cuda: unavailable");
  expect_one_line_error("view --scene builtin:box --device cuda", "--device cuda: unavailable");
}

// Quality per ray runs on either device: auto picks the GPU where there is one, cuda is refused
// only for want of a GPU, and a temporal sequence builds on its history on both.
TEST(DeviceCli, QualityPerRayRunsOnTheChosenDevice) {
  const std::string options = "render --scene builtin:box --size 80x50 --max-rays 16 --adaptive --denoise --temporal --frames 3 ";
  const CliRun r = foveal_test::foveal(options + "--stats dev_reuse.json -o dev_reuse.png");
  ASSERT_EQ(r.status, 0) << r.err;
  const bool cuda = foveal::availability().usable;
  EXPECT_NE(r.out.find(cuda ? "device   cuda (" : "device   cpu ("), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("dev_reuse.json")));
  EXPECT_EQ(j["device"], cuda ? "cuda" : "cpu");
  EXPECT_GT(j["reuse"]["history_pixels"].get<int>(), 1000);
  if (!cuda) expect_one_line_error(options + "-o dev_reuse_cuda.png --device cuda", "--device cuda: unavailable");
}

// The vision simulation and its benchmark name their device; on a GPU the benchmark runs the CPU
// beside it and reports the ratio and how far the two agree.
TEST(DeviceCli, SimulateAndBenchVisionNameTheirDevice) {
  const CliRun r = foveal_test::foveal(
      "simulate --scene builtin:box --size 64x48 --steps 3 --save-steps '' -o dev_sim --stats dev_sim.json --device cpu");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("device   cpu"), std::string::npos) << r.out;
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(scratch("dev_sim.json")))["device"], "cpu");
  const CliRun b = foveal_test::foveal("bench vision --scene builtin:box --size 64x48 --steps 2 --json dev_vision.json");
  ASSERT_EQ(b.status, 0) << b.err;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("dev_vision.json")));
  ASSERT_EQ(j["rows"].size(), 1u);
  const auto& row = j["rows"][0];
  if (!foveal::availability().usable) {
    EXPECT_EQ(row["device"], "cpu");
    EXPECT_FALSE(row.contains("cpu_over_gpu"));
    return;
  }
  EXPECT_EQ(row["device"], "cuda");
  EXPECT_GT(row["cpu_over_gpu"].get<double>(), 0);
  EXPECT_NEAR(row["cpu_over_gpu"].get<double>(), row["cpu"]["time_ms"]["total"].get<double>() / row["time_ms"]["total"].get<double>(),
              1e-6);
  EXPECT_LT(row["agreement"]["perceived_mean_abs_diff"].get<double>(), 0.01);
}

TEST(DeviceCli, ReplayNamesItsDevice) {
  const std::string recording = write_three_fixations("device_replay.csv");
  const CliRun r = foveal_test::foveal("replay --gaze " + recording +
                                       " --screen 480x300 --scene builtin:box --size 48x30 --max-rays 4 --frames 3 "
                                       "-o dev_replay --stats dev_replay.json --device cpu");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("device   cpu"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("dev_replay.json")));
  EXPECT_EQ(j["device"], "cpu");
  EXPECT_EQ(j["frames"], 3);
}

}  // namespace
}  // namespace foveal_test
