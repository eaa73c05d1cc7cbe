// Tests of `foveal perceive`: the user's own stimuli through an impaired eye.
#include "cli_helpers.h"

#include "foveal/impair/cvd.h"
#include "foveal/io/image_io.h"
#include "foveal/io/video.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>

using namespace foveal_test;
namespace fs = std::filesystem;

namespace {

CliRun run_cli(const std::string& args) { return foveal_test::foveal(args); }

// A colourful linear test image
foveal::Image test_image(int w, int h) {
  foveal::Image im(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      im.at(x, y, 0) = 0.5f + 0.4f * std::sin(x * 0.3f);
      im.at(x, y, 1) = 0.5f + 0.4f * std::cos(y * 0.2f + x * 0.05f);
      im.at(x, y, 2) = float(x + y) / float(w + h);
    }
  return im;
}

// Vertical bars, period 8 px, in every channel
foveal::Image grating(int w, int h) {
  foveal::Image im(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = 0.5f + 0.3f * std::sin(2 * std::numbers::pi * x / 8.0);
  return im;
}

// Peak-to-peak of a column window's green values around row y
double contrast_near(const foveal::Image& im, int x0, int x1, int y) {
  float lo = 1e9f, hi = -1e9f;
  for (int x = x0; x < x1; ++x) {
    lo = std::min(lo, im.at(x, y, 1));
    hi = std::max(hi, im.at(x, y, 1));
  }
  return hi - lo;
}

// A `frames`-frame video of test_image(w, h) at 10 fps in the scratch folder; the error text when
// ffmpeg cannot make it (the test skips).
std::optional<std::string> write_test_video(const std::string& name, int frames, int w, int h) {
  const std::string dir = name + "-frames";
  fs::create_directories(scratch(dir));
  for (int k = 0; k < frames; ++k)
    foveal::save_image(test_image(w, h), scratch(dir + "/frame_" + std::to_string(10000 + k).substr(1) + ".png").string());
  try {
    foveal::encode_video(scratch(dir + "/frame_%04d.png").string(), 10, scratch(name).string());
  } catch (const std::exception& e) {
    return std::string(e.what());
  }
  return std::nullopt;
}

}  // namespace

TEST(PerceiveCli, LinearFloatInAndOutIsExact) {
  const foveal::Image in = test_image(64, 40);
  foveal::save_image(in, scratch("in.exr").string());
  foveal::save_image(in, scratch("in.pfm").string());
  // a healthy eye without optics: the very same floats, EXR and PFM
  for (const char* ext : {"exr", "pfm"}) {
    const CliRun r = run_cli(std::string("perceive in.") + ext + " -o same." + ext + " --no-optics -q");
    ASSERT_EQ(r.status, 0) << r.err;
    const foveal::Image out = foveal::load_image(scratch(std::string("same.") + ext).string());
    ASSERT_EQ(out.pixels.size(), in.pixels.size());
    for (size_t i = 0; i < in.pixels.size(); ++i) ASSERT_EQ(out.pixels[i], in.pixels[i]) << ext << " value " << i;
  }
  // deuteranopia (Machado 1.0) on linear values: the matrix applied to the stored floats
  const CliRun r = run_cli("perceive in.exr -o deutan.exr --no-optics --eye cvd:deutan:1 -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const foveal::Image out = foveal::load_image(scratch("deutan.exr").string());
  const glm::dmat3 m = foveal::machado_table(foveal::CvdType::deutan, 10);
  for (size_t p = 0; p < size_t(in.width) * in.height; ++p) {
    const glm::dvec3 c(in.pixels[p * 3], in.pixels[p * 3 + 1], in.pixels[p * 3 + 2]);
    const glm::dvec3 e = m * c;
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(out.pixels[p * 3 + k], std::max(0.0, e[k]), 1e-6);
  }
}

TEST(PerceiveCli, EightBitImagesAreDecodedFromSrgbAndEncodedBack) {
  const foveal::Image in = test_image(64, 40);
  foveal::save_image(in, scratch("in.png").string());  // sRGB-encoded bytes
  const CliRun r = run_cli("perceive in.png -o ach.png --no-optics --eye achromatopsia -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const foveal::Image png_in = foveal::load_image(scratch("in.png").string()), out = foveal::load_image(scratch("ach.png").string());
  auto lin = [](float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); };
  for (size_t p = 0; p < size_t(in.width) * in.height; p += 7) {
    const double y =
        0.2126729 * lin(png_in.pixels[p * 3]) + 0.7151522 * lin(png_in.pixels[p * 3 + 1]) + 0.0721750 * lin(png_in.pixels[p * 3 + 2]);
    EXPECT_NEAR(out.pixels[p * 3], foveal::linear_to_srgb(static_cast<float>(y)), 1.0 / 255 + 1e-6);
    EXPECT_EQ(out.pixels[p * 3], out.pixels[p * 3 + 1]);
  }
}

TEST(PerceiveCli, ARecordingsFixationsMoveTheFieldWithTheFramesTime) {
  // four frames at 4 fps; a recording fixates x = 100 for 0.45 s, then x = 300 (the saccade, one
  // sample long, well before the third frame at 0.5 s)
  fs::create_directories(scratch("frames"));
  for (int k = 0; k < 4; ++k) foveal::save_image(grating(400, 200), scratch("frames/f" + std::to_string(k) + ".png").string());
  {
    std::ofstream csv(scratch("gaze.csv"));
    csv << "t,x,y\n";
    for (int i = 0; i < 100; ++i) csv << i * 0.01 << "," << (i < 45 ? 100 : 300) << ",100\n";
  }
  const CliRun r =
      run_cli("perceive frames -o seen --fps 4 --gaze gaze.csv --screen 400x200 --eye field:hemianopia:left:20 --no-optics -q");
  ASSERT_EQ(r.status, 0) << r.err;
  for (int k = 0; k < 4; ++k) {
    const foveal::Image out = foveal::load_image(scratch("seen/f" + std::to_string(k) + ".png").string());
    const int fix = k < 2 ? 100 : 300;
    // left of the fixation the grating is gone, right of it kept
    EXPECT_LT(contrast_near(out, fix - 60, fix - 30, 100), 0.1) << "frame " << k;
    EXPECT_GT(contrast_near(out, fix + 30, fix + 60, 100), 0.3) << "frame " << k;
  }
}

TEST(PerceiveCli, VideosGoThroughFfmpegFrameByFrame) {
  if (const auto no_video = write_test_video("in.mp4", 5, 64, 48)) GTEST_SKIP() << "skipped: no ffmpeg (" << *no_video << ")";
  const CliRun r = run_cli("perceive in.mp4 -o out.mp4 --eye cvd:protanopia --gaze 20,20");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("5 frames at 10 fps"), std::string::npos) << r.out;
  fs::create_directories(scratch("vout"));
  EXPECT_EQ(foveal::decode_video(scratch("out.mp4").string(), scratch("vout/%04d.png").string()), 10.0);
  EXPECT_EQ(std::distance(fs::directory_iterator(scratch("vout")), fs::directory_iterator{}), 5);
}

TEST(PerceiveCli, AmslerGridAndFieldMapPictures) {
  const CliRun r = run_cli("perceive builtin:amsler -o amsler.png --eye amd:4:0.4 --field-map map.png -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const foveal::Image grid = foveal::load_image(scratch("amsler.png").string()), map = foveal::load_image(scratch("map.png").string());
  EXPECT_EQ(grid.width, 440);  // 22° at 20 px/°
  EXPECT_EQ(map.width, 600);
  // the map is dark at the centre and white 20° out
  EXPECT_NEAR(map.at(305, 295, 0), 1.0 - 25.0 / 30.0, 0.01);  // the scotoma: 25 dB on a 0–30 dB scale
  EXPECT_GT(map.at(320, 120, 0), 0.9f);
}

TEST(PerceiveCli, ProfilesWithFieldFilesWork) {
  {
    std::ofstream f(scratch("od.csv"));
    f << "total_deviation_db\n";
    for (int i = 0; i < 54; ++i) f << (i < 27 ? -25 : 0) << "\n";  // the upper half of the 24-2 lost
    std::ofstream p(scratch("patient.json"));
    p << R"({"age": 64, "eyes": {"OD": {"field": {"file": "od.csv", "grid": "24-2"}}}})";
  }
  foveal::save_image(grating(400, 300), scratch("g.png").string());
  const CliRun r = run_cli("perceive g.png -o g-seen.png --eye patient.json --no-optics --display 40,30,50 -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const foveal::Image out = foveal::load_image(scratch("g-seen.png").string());
  EXPECT_LT(contrast_near(out, 150, 250, 60), 0.1);   // above the fixation: lost
  EXPECT_GT(contrast_near(out, 150, 250, 240), 0.3);  // below: seen
}

TEST(PerceiveCli, BadInputGivesOneClearLine) {
  foveal::save_image(test_image(32, 20), scratch("small.png").string());
  foveal::save_image(test_image(16, 10), scratch("depth.exr").string());
  {
    std::ofstream f(scratch("bad-field.csv"));
    f << "x_deg,y_deg,total_deviation_db\n3,3,-2\n3,3,-4\n";
    std::ofstream p(scratch("bad.json"));
    p << R"({"eyes": {"OD": {"refraction": -2, "sphere": 1}}})";
    std::ofstream g(scratch("g.csv"));
    g << "t,x,y\n0,1,1\n";
  }
  expect_one_line_error("perceive small.png -o o.png --eye field:bad-field.csv", "bad-field.csv:3: location (3, 3) of OD appears twice");
  expect_one_line_error("perceive small.png -o o.png --eye bad.json", "bad.json: /eyes/OD/sphere: unknown key");
  expect_one_line_error("perceive small.png -o o.png --eye cvd:purple", "unknown colour-vision deficiency 'purple'");
  expect_one_line_error("perceive small.png -o o.png --gaze g.csv", "needs a video or a folder of frames");
  expect_one_line_error("perceive small.png -o o.png --depth depth.exr", "--depth: 16x10, the input is 32x20");
  expect_one_line_error("perceive missing.png -o o.png", "missing.png: no such image, folder or video");
  expect_one_line_error("perceive small.png -o o.png --gaze pupil://127.0.0.1:1", "perceive takes a point or a recording");
  expect_one_line_error("perceive small.png -o o.png --eye field:24-2", "name the file of values");
}

// Hostile input: a failed video run leaves no decoded frames behind (they went to a temporary
// folder that stayed), and --pupil 0 is refused instead of meaning the default 3.5 mm.
TEST(PerceiveCli, AFailedVideoRunLeavesNoTemporaryFilesAndPupilZeroIsRefused) {
  if (const auto no_video = write_test_video("hin.mp4", 3, 32, 24)) GTEST_SKIP() << "skipped: no ffmpeg (" << *no_video << ")";
  foveal::save_image(test_image(8, 8), scratch("small-depth.pfm").string());  // not the video's size
  fs::create_directories(scratch("private-tmp"));
  const CliRun r = run_cli("perceive hin.mp4 -o hout.mp4 --depth small-depth.pfm");  // fails after decoding
  EXPECT_EQ(r.status, 1) << r.err;
  const CliRun t =
      foveal_test::run_foveal("TMPDIR='" + scratch("private-tmp").string() + "'", "perceive hin.mp4 -o hout.mp4 --depth small-depth.pfm");
  EXPECT_EQ(t.status, 1) << t.err;
  EXPECT_NE(t.err.find("--depth"), std::string::npos) << t.err;
  EXPECT_EQ(std::distance(fs::directory_iterator(scratch("private-tmp")), fs::directory_iterator{}), 0)
      << "decoded frames left behind in the temporary folder";
  EXPECT_FALSE(fs::exists(scratch("hout.mp4")));
  foveal::save_image(test_image(32, 24), scratch("hstim.png").string());
  expect_one_line_error("perceive hstim.png -o hseen.png --pupil 0", "--pupil: must be in (0, 10] mm, got 0");
}
