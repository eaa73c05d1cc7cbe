// `foveal compare` as a user runs it on two renders.
#include "cli_helpers.h"
#include "foveal/io/image_io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace foveal_test {
namespace {

TEST(CompareCli, BandsJsonErrorMapAndPlot) {
  const std::string common = "render --scene builtin:box --size 200x125 --gaze 60,50 -q --max-rays 32";
  ASSERT_EQ(foveal(common + " -o fov.png").status, 0);
  ASSERT_EQ(foveal(common + " --mode full --seed 2 -o ref.png").status, 0);
  ASSERT_EQ(foveal(common + " --mode full --seed 3 -o ref2.png").status, 0);
  const CliRun r = foveal("compare fov.png ref.png --reference2 ref2.png --gaze 60,50 --json cmp.json --error-map err.png --plot err_plot.png");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("q(E)=1"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("cmp.json")));
  ASSERT_EQ(j["bands"].size(), 6u);
  EXPECT_EQ(j["bands"][0]["name"], "0-2.5");
  EXPECT_EQ(j["bands"][5]["name"], "q=1");
  size_t pixels = 0;
  for (int k = 0; k < 5; ++k) pixels += j["bands"][k]["error"]["pixels"].get<size_t>();
  EXPECT_EQ(pixels, 200u * 125u);
  EXPECT_GT(j["bands"][4]["noise_ratio"].get<double>(), j["bands"][0]["noise_ratio"].get<double>());  // worse away from the gaze
  const foveal::Image map = foveal::load_image(scratch("err.png").string());
  EXPECT_EQ(map.width, 200);
  const foveal::Image plot = foveal::load_image(scratch("err_plot.png").string());
  EXPECT_GT(plot.width, 100);
  // The same image against itself: infinite PSNR, written as "inf"
  const CliRun same = foveal("compare ref.png ref.png --json same.json -q");
  ASSERT_EQ(same.status, 0) << same.err;
  const auto s = nlohmann::json::parse(std::ifstream(scratch("same.json")));
  EXPECT_EQ(s["whole"]["psnr_db"], "inf");
  EXPECT_EQ(s["whole"]["ssim"], 1.0);
}

TEST(CompareCli, BadInputIsOneClearLine) {
  ASSERT_EQ(foveal("render --scene builtin:plane --size 40x30 -q -o small.png").status, 0);
  ASSERT_EQ(foveal("render --scene builtin:plane --size 30x40 -q -o tall.png").status, 0);
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {"compare small.png tall.png", "same size"},
           {"compare small.png missing.png", "missing.png"},
           {"compare small.png small.png --gaze 1", "--gaze"},
           {"compare small.png small.png --ellipse 0", "--ellipse"}})
    expect_one_line_error(args, expected);
}

}  // namespace
}  // namespace foveal_test
