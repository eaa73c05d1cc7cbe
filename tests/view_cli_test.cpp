// `foveal view` as a script runs it: a window under Xvfb (software OpenGL), N frames, a screenshot.
#include "cli_helpers.h"
#include "fake_pupil.h"
#include "foveal/io/image_io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace foveal_test {
namespace {

bool have_xvfb() { return std::system("command -v xvfb-run > /dev/null 2>&1") == 0; }

// `foveal view ARGS` under a virtual display (or another launcher). Leak checking is off for it:
// Mesa's drivers keep allocations until the process ends. Concurrent tests look for a free X
// display from different numbers (xvfb-run -a alone can race).
CliRun run_view(const std::string& args, std::string launcher = "") {
  if (launcher.empty()) launcher = "xvfb-run -a -n " + std::to_string(100 + ::getpid() % 800) + " -s '-screen 0 1280x1024x24'";
  return run_foveal("ASAN_OPTIONS=detect_leaks=0 " + launcher, "view " + args + " < /dev/null");
}

nlohmann::json read_json(const std::string& name) {
  std::ifstream in(scratch(name));
  return nlohmann::json::parse(in);
}

TEST(ViewCli, ScreenshotIsTheRenderCommandsImage) {
  if (!have_xvfb()) GTEST_SKIP() << "skipped: xvfb-run absent (Debian package xvfb)";
  const std::string common = "--scene builtin:box --size 240x150 --gaze 70,60 --max-rays 48";
  const CliRun v = run_view(common + " --frames 3 --overlays none --screenshot view.png --window-screenshot window.png");
  ASSERT_EQ(v.status, 0) << v.err;
  const CliRun r = foveal_test::foveal("render " + common + " -o render.png -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const foveal::Image a = foveal::load_image(scratch("view.png").string()), b = foveal::load_image(scratch("render.png").string());
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  EXPECT_EQ(a.pixels, b.pixels);
  // The window shows those pixels: at scale 1, centred in the 640-pixel-high area left of the 340-pixel panel
  const foveal::Image win = foveal::load_image(scratch("window.png").string());
  ASSERT_EQ(win.width, 240 + 340);
  ASSERT_EQ(win.height, 640);
  size_t same = 0;
  for (int y = 0; y < 150; ++y)
    for (int x = 0; x < 240; ++x) same += win.at(x, 245 + y, 0) == a.at(x, y, 0) && win.at(x, 245 + y, 1) == a.at(x, y, 1);
  EXPECT_GT(same, 240u * 150u * 99 / 100);
  const nlohmann::json j = read_json("view.json");
  EXPECT_EQ(j["converged"], true);
  EXPECT_EQ(j["render_gaze_px"][0], 70.0);
  EXPECT_GT(j["frame"]["ao_rays_per_second"].get<double>(), 0.0);
  EXPECT_GT(j["ui_frame_ms"].get<double>(), 0.0);  // the frame time is measured
}

TEST(ViewCli, SideBySideAndVisionScreenshotsWithOverlays) {
  if (!have_xvfb()) GTEST_SKIP() << "skipped: xvfb-run absent (Debian package xvfb)";
  const CliRun s = run_view(
      "--scene builtin:box --size 200x120 --gaze 60,50 --max-rays 32 --mode side-by-side --overlays all --frames 2 "
      "--screenshot sbs.png");
  ASSERT_EQ(s.status, 0) << s.err;
  const foveal::Image sbs = foveal::load_image(scratch("sbs.png").string());
  EXPECT_EQ(sbs.width, 600);  // foveated | reference | difference
  EXPECT_EQ(sbs.height, 120);
  EXPECT_NEAR(sbs.at(60, 50, 0), 1.0f, 1e-6f);  // the gaze cross on every pane
  EXPECT_NEAR(sbs.at(260, 50, 0), 1.0f, 1e-6f);
  const CliRun v =
      run_view("--scene builtin:box --size 200x120 --gaze 60,50 --mode vision --eye myopia:-3 --frames 2 --screenshot vision.png");
  ASSERT_EQ(v.status, 0) << v.err;
  const nlohmann::json j = read_json("vision.json");
  EXPECT_EQ(j["settings"]["eye"]["preset"], "myopia:-3");
  EXPECT_EQ(j["vision_step"]["step"], 1);
  EXPECT_NEAR(j["vision_step"]["focus_px"][0].get<double>(), 60, 1e-3);
}

TEST(ViewCli, RecordedGazeDrivesTheView) {
  if (!have_xvfb()) GTEST_SKIP() << "skipped: xvfb-run absent (Debian package xvfb)";
  // Three fixations on a 480×300 screen, played 10× faster than recorded: after 60 frames it has ended on the last, (240, 150)
  const std::string rec = write_three_fixations("view_gaze.csv");
  const CliRun v = run_view("--scene builtin:box --size 240x150 --max-rays 16 --gaze " + rec +
                            " --screen 480x300 --speed 10 --frames 60 --overlays gaze,scanpath --screenshot rec.png");
  ASSERT_EQ(v.status, 0) << v.err;
  const nlohmann::json j = read_json("rec.json");
  EXPECT_NEAR(j["fixation_px"][0].get<double>(), 120, 0.5);  // (240, 150) on the screen → (120, 75) in the render
  EXPECT_NEAR(j["fixation_px"][1].get<double>(), 75, 0.5);
  EXPECT_NEAR(j["render_gaze_px"][0].get<double>(), 120, 0.5);
  EXPECT_NE(j["gaze_source"].get<std::string>().find("ended"), std::string::npos);
}

TEST(ViewCli, LiveTrackerThatHangsUpDoesNotStopTheView) {
  if (!have_xvfb()) GTEST_SKIP() << "skipped: xvfb-run absent (Debian package xvfb)";
  FakePupil fake;
  std::vector<std::pair<std::string, std::string>> messages;
  for (int i = 0; i < 60; ++i) messages.emplace_back("surfaces.screen", surface_gaze(0.25, 0.75, true, 10 + 0.004 * i));
  for (int i = 0; i < 60; ++i) messages.emplace_back("surfaces.screen", surface_gaze(0.75, 0.25, true, 10.3 + 0.004 * i));
  fake.serve(messages, true, nullptr);
  // At most 60 frames a second: 240 frames leave the tracker (120 messages, then the hang-up) at
  // least 4 s, ample also on a loaded machine
  const CliRun v = run_view("--gaze '" + fake.url("surface=screen") +
                            "' --screen 400x200 --size 80x40 --max-rays 8 --frames 240 "
                            "--screenshot live.png");
  ASSERT_EQ(v.status, 0) << v.err;
  const nlohmann::json j = read_json("live.json");
  // norm (0.75, 0.25) of 400×200 (origin bottom-left) → (300, 150) on the screen → (60, 30) in the 80×40 render
  EXPECT_NEAR(j["fixation_px"][0].get<double>(), 60, 1e-3);
  EXPECT_NEAR(j["fixation_px"][1].get<double>(), 30, 1e-3);
  EXPECT_NE(j["gaze_source"].get<std::string>().find("disconnected"), std::string::npos) << j["gaze_source"];
}

TEST(ViewCli, NoDisplayAndBadOptionsAreOneClearLine) {
  const CliRun no_display = run_view("--frames 1 --screenshot x.png --size 64x64", "env -u DISPLAY -u WAYLAND_DISPLAY");
  EXPECT_EQ(no_display.status, 1) << no_display.err;
  EXPECT_NE(no_display.err.find("needs a display"), std::string::npos) << no_display.err;
  EXPECT_EQ(lines(no_display.err), 1u) << no_display.err;
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {"view --mode fullscreen", "unknown view mode 'fullscreen'"},
           {"view --overlays gaze,heat", "unknown overlay 'heat'"},
           {"view --frames 3", "--screenshot"},
           {"view --gaze no_such_recording.asc", "no_such_recording.asc"},
           {"view --margin-ms 3", "--margin-ms needs --realtime"},
           {"view --periphery-share 0.5", "--periphery-share needs --realtime"},
           {"view --min-scale 0.5", "--min-scale needs --realtime"},
           {"view --realtime --min-scale 0", "--min-scale: must be in (0, 1]"},
           {"view --realtime --margin-ms 10", "--margin-ms: must be in [0, the frame budget 10 ms)"},
           {"view --realtime --periphery-share 2", "--periphery-share: must be in (0, 1]"}})
    expect_one_line_error(args, expected);
}

}  // namespace
}  // namespace foveal_test
