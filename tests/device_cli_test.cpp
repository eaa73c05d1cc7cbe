// `--device` as a user meets it: cpu always, cuda only where a GPU answers, and the device named.
#include "cli_helpers.h"
#include "foveal/cuda/gpu.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace foveal_test {
namespace {

TEST(DeviceCli, CpuRunsAndTheChoiceIsPrinted) {
  const CliRun r = foveal("render --scene builtin:box --size 80x50 --max-rays 8 --device cpu --stats dev.json -o dev.png");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("device   cpu"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("dev.json")));
  EXPECT_EQ(j["device"], "cpu");
  // auto picks what is there and says so
  const CliRun a = foveal("render --scene builtin:box --size 80x50 --max-rays 8 -o dev_auto.png");
  ASSERT_EQ(a.status, 0) << a.err;
  EXPECT_NE(a.out.find(foveal::gpu::availability().usable ? "device   cuda (" : "device   cpu (no GPU: "), std::string::npos)
      << a.out;
}

TEST(DeviceCli, UnknownOrUnavailableDeviceIsOneLine) {
  expect_one_line_error("render --scene builtin:box --device opencl", "--device: unknown device 'opencl' (known: auto, cpu, cuda)");
  expect_one_line_error("bench ao --scene builtin:box --device tpu", "--device: unknown device 'tpu'");
  if (foveal::gpu::availability().usable) GTEST_SKIP() << "a GPU is usable here: --device cuda is not refused";
  expect_one_line_error("render --scene builtin:box --device cuda",
                        "--device cuda: unavailable: " + foveal::gpu::availability().reason);
  expect_one_line_error("bench ao --scene builtin:box --device cuda", "--device cuda: unavailable");
  const std::string recording = write_three_fixations("device_three.csv");
  expect_one_line_error("replay --gaze " + recording + " --screen 480x300 --scene builtin:box --size 48x30 --frames 2 -o dev_replay --device cuda",
                        "--device cuda: unavailable");
}

TEST(DeviceCli, ReplayNamesItsDevice) {
  const std::string recording = write_three_fixations("device_replay.csv");
  const CliRun r = foveal("replay --gaze " + recording + " --screen 480x300 --scene builtin:box --size 48x30 --max-rays 4 --frames 3 "
                          "-o dev_replay --stats dev_replay.json --device cpu");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("device   cpu"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("dev_replay.json")));
  EXPECT_EQ(j["device"], "cpu");
  EXPECT_EQ(j["frames"], 3);
}

}  // namespace
}  // namespace foveal_test
