// `foveal compare` as a user runs it on two renders.
#include "cli_helpers.h"
#include "foveal/cuda/gpu.h"
#include "foveal/io/image_io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace foveal_test {
namespace {

// builtin:box as fov.png (seed 1) and the full-frame references ref.png (seed 2) and ref2.png (seed 3).
void render_foveated_and_references(const std::string& options) {
  const std::string common = "render --scene builtin:box -q " + options;
  ASSERT_EQ(foveal_test::foveal(common + " -o fov.png").status, 0);
  ASSERT_EQ(foveal_test::foveal(common + " --mode full --seed 2 -o ref.png").status, 0);
  ASSERT_EQ(foveal_test::foveal(common + " --mode full --seed 3 -o ref2.png").status, 0);
}

std::string fmt_ratio(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

TEST(CompareCli, BandsJsonErrorMapAndPlot) {
  render_foveated_and_references("--size 200x125 --gaze 60,50 --max-rays 32");
  const CliRun r = foveal_test::foveal(
      "compare fov.png ref.png --reference2 ref2.png --gaze 60,50 --json cmp.json --error-map err.png --plot err_plot.png");
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
  const CliRun same = foveal_test::foveal("compare ref.png ref.png --json same.json -q");
  ASSERT_EQ(same.status, 0) << same.err;
  const auto s = nlohmann::json::parse(std::ifstream(scratch("same.json")));
  EXPECT_EQ(s["whole"]["psnr_db"], "inf");
  EXPECT_EQ(s["whole"]["ssim"], 1.0);
}

TEST(CompareCli, BadInputIsOneClearLine) {
  ASSERT_EQ(foveal_test::foveal("render --scene builtin:plane --size 40x30 -q -o small.png").status, 0);
  ASSERT_EQ(foveal_test::foveal("render --scene builtin:plane --size 30x40 -q -o tall.png").status, 0);
  for (const auto& [args, expected] :
       std::vector<std::pair<std::string, std::string>>{{"compare small.png tall.png", "same size"},
                                                        {"compare small.png missing.png", "missing.png"},
                                                        {"compare small.png small.png --gaze 1", "--gaze"},
                                                        {"compare small.png small.png --ellipse 0", "--ellipse"},
                                                        {"compare small.png small.png --ssim-border mirror", "--ssim-border"}})
    expect_one_line_error(args, expected);
}

TEST(CompareCli, MarkdownTableAndAcuityWeightedError) {
  render_foveated_and_references("--size 160x100 --gaze 40,50 --max-rays 16");
  const CliRun r = foveal_test::foveal("compare fov.png ref.png --reference2 ref2.png --gaze 40,50 --json w.json --markdown w.md");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("w.json")));
  const double w = j["acuity_weighted_rmse"], wn = j["acuity_weighted_noise_rmse"];
  EXPECT_NEAR(j["acuity_weighted_ratio"].get<double>(), w / wn, 1e-9);
  // A weighted mean of the pixels' squared errors: the bands 0–2.5° … 20°+ cover the image, so it lies
  // between the smallest and the largest band RMSE
  double lo = 1e9, hi = 0;
  for (int k = 0; k < 5; ++k)
    if (j["bands"][k]["error"]["pixels"].get<size_t>() > 0) {
      lo = std::min(lo, j["bands"][k]["error"]["rmse"].get<double>());
      hi = std::max(hi, j["bands"][k]["error"]["rmse"].get<double>());
    }
  EXPECT_GT(w, 0.0);
  EXPECT_GE(w, lo);
  EXPECT_LE(w, hi);
  std::stringstream md;
  md << std::ifstream(scratch("w.md")).rdbuf();
  const std::string table = md.str();
  EXPECT_NE(table.find("| q(E) = 1 |"), std::string::npos) << table;
  EXPECT_NE(table.find(fmt_ratio(j["bands"][5]["noise_ratio"].get<double>())), std::string::npos) << table;
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 2 + 7 + 2);  // header, rule, whole + 6 bands, blank, weighted
}

TEST(BenchQualityCli, SweepTableJsonAndPlot) {
  const CliRun r = foveal_test::foveal(
      "bench quality --scene builtin:box --size 120x75 --reference-rays 16 --gamma 1,3 --max-rays 8,16 "
      "--beta 1 --gaze 30,40 --gaze 90,20 --json q.json --markdown q.md --plot q.png");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("q.json")));
  ASSERT_EQ(j["points"].size(), 8u);  // 2 γ × 2 n_max × 2 methods (paper, adaptive+denoise) × 1 β
  EXPECT_EQ(j["points"][0]["method"], "paper");
  EXPECT_EQ(j["points"][1]["method"], "adaptive+denoise");
  EXPECT_EQ(j["fovea_floors"].size(), 2u);  // one per gaze
  bool any_front = false;
  for (const auto& p : j["points"]) {
    ASSERT_EQ(p["gazes"].size(), 2u);
    EXPECT_NEAR(p["speedup"].get<double>(), j["reference_ms"].get<double>() / p["ms"].get<double>(), 1e-6);
    any_front |= p["pareto"].get<bool>();
  }
  EXPECT_TRUE(any_front);
  // More rays at the same γ: a smaller ray ratio
  EXPECT_GT(j["points"][0]["ray_ratio"].get<double>(), j["points"][2]["ray_ratio"].get<double>());
  std::stringstream md;
  md << std::ifstream(scratch("q.md")).rdbuf();
  const std::string table = md.str();
  // preface, blank, the fovea's floor, blank, header, rule, 8 rows
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 2 + 2 + 2 + 8);
  EXPECT_NE(table.find("| adaptive+denoise | 3 | 16 | 1 |"), std::string::npos) << table;
  const foveal::Image plot = foveal::load_image(scratch("q.png").string());
  EXPECT_EQ(plot.width, 1300);                               // two panels: still error and flicker
  EXPECT_EQ(r.out.find("the defaults"), std::string::npos);  // not in the grid: no line about them
  EXPECT_NE(r.out.find("recommended"), std::string::npos) << r.out;
}

TEST(BenchQualityCli, SequenceRunsTheConfigurationsAskedForAndPlotsThem) {
  const CliRun r = foveal_test::foveal(
      "bench quality --sequence --scene builtin:box --size 60x40 --frames 3 --reference-rays 8 "
      "--configs denoise+temporal,paper --json s.json --markdown s.md --plot s.png");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(std::ifstream(scratch("s.json")));
  ASSERT_EQ(j["configs"].size(), 2u);  // in the order given, named canonically
  EXPECT_EQ(j["configs"][0]["name"], "temporal+denoise");
  EXPECT_TRUE(j["configs"][0]["temporal"].get<bool>() && j["configs"][0]["denoise"].get<bool>());
  EXPECT_FALSE(j["configs"][0]["adaptive"].get<bool>());
  EXPECT_EQ(j["configs"][1]["name"], "paper");
  EXPECT_EQ(j["device"], "cpu");  // the default, the same as --device cpu
  std::stringstream md;
  md << std::ifstream(scratch("s.md")).rdbuf();
  EXPECT_NE(md.str().find("| temporal+denoise |"), std::string::npos) << md.str();
  const foveal::Image plot = foveal::load_image(scratch("s.png").string());
  EXPECT_EQ(plot.width, 1300);
}

TEST(BenchQualityCli, BadOptionsAreOneClearLine) {
  const std::string base = "bench quality --scene builtin:plane --size 40x30 ";
  for (const auto& [args, expected] :
       std::vector<std::pair<std::string, std::string>>{{base + "--max-rays 0", "--max-rays"},
                                                        {base + "--max-rays 2.5", "--max-rays"},
                                                        {base + "--gamma 0", "--gamma"},
                                                        {base + "--beta -1", "--beta"},
                                                        {base + "--gamma x", "--gamma"},
                                                        {base + "--gazes nowhere", "nowhere"},
                                                        {base + "--gaze 3", "--gaze"},
                                                        {base + "--recording x.csv", "--sequence"},
                                                        {base + "--sequence --recording missing.csv", "missing.csv"},
                                                        {base + "--configs paper,temporal", "--sequence"},
                                                        {base + "--configs adaptive+sharpen", "sharpen"},
                                                        {base + "--sequence --configs paper,paper", "paper is listed twice"},
                                                        {base + "--sequence --device opencl", "--device: unknown device 'opencl'"}})
    expect_one_line_error(args, expected);
  // The GPU measures sequences; without one, --device cuda says why
  if (foveal::availability().usable)
    expect_one_line_error(base + "--device cuda", "the single-frame sweep runs on the CPU");
  else
    expect_one_line_error(base + "--sequence --device cuda", "--device cuda: unavailable");
}

}  // namespace
}  // namespace foveal_test
