// The viewer's session and overlays, without a window: every shown pixel comes from the library's
// render and simulation functions, the gaze pipeline follows the mouse, overlays sit where the
// foveation model says.
#include "foveal/cuda/gpu.h"
#include "foveal/io/plot.h"
#include "foveal/ui/overlays.h"
#include "foveal/ui/session.h"
#include "foveal/io/image_io.h"
#include "foveal/util/error.h"
#include "test_scenes.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <tuple>
#include <unistd.h>

namespace foveal {
namespace {

using foveal_test::box;
const Tracer& box_tracer() {
  static const Tracer tracer(box());
  return tracer;
}

ViewSettings small_settings(ViewMode mode) {
  ViewSettings s;
  s.mode = mode;
  s.render.width = 160;
  s.render.height = 100;  // filling the default 1680×1050 display: q(E) falls over the image
  s.render.foveation.max_rays = 24;
  return s;
}

GazeInput fixed(glm::dvec2 p) {
  GazeInput g;
  g.fixed_px = p;
  return g;
}

size_t differing(const Rgba8& a, int x0, const Rgba8& b) {
  size_t n = 0;
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; ++x)
      for (int c = 0; c < 3; ++c) n += a.at(x0 + x, y)[c] != b.at(x, y)[c];
  return n;
}

const Overlays kNone = parse_overlays("none");

TEST(ViewSession, FinishedFrameIsTheRenderersFrame) {
  const Camera camera = default_camera(box());
  ViewSettings s = small_settings(ViewMode::foveated);
  ViewSession session(box(), box_tracer(), camera, s, fixed({50, 40}));
  ASSERT_TRUE(session.wait_until_converged(120, kNone));
  RenderParams p = s.render;
  p.gaze_px = glm::dvec2(50, 40);
  const Frame frame = render_frame(box_tracer(), box(), camera, p);
  const Rgba8 expected = to_rgba8(frame.color);
  ASSERT_EQ(session.image().width, expected.width);
  EXPECT_EQ(differing(session.image(), 0, expected), 0u);
  EXPECT_EQ(session.status().ao_rays, frame.stats.ao_rays);
  EXPECT_EQ(session.status().render_gaze, glm::dvec2(50, 40));

  // A changed parameter restarts the render, which finishes at the new parameters' frame
  s.render.foveation.gamma = 1.0;
  session.set_settings(s);
  session.update(kNone);
  EXPECT_FALSE(session.status().converged);
  ASSERT_TRUE(session.wait_until_converged(120, kNone));
  p.foveation.gamma = 1.0;
  const Frame second = render_frame(box_tracer(), box(), camera, p);
  EXPECT_GT(second.stats.ao_rays, frame.stats.ao_rays);  // γ = 1 spends more rays off the fovea
  EXPECT_EQ(session.status().ao_rays, second.stats.ao_rays);
  EXPECT_EQ(differing(session.image(), 0, to_rgba8(second.color)), 0u);
}

// --realtime: every update() is one frame of the real-time loop; the fovea converges at the fixed
// gaze, and the finished fovea's pixels are the renderer's (the same rays of the same sequences).
TEST(ViewSession, RealtimeUpdatesAreFramesOfTheLoop) {
  const Camera camera = default_camera(box());
  ViewSettings s = small_settings(ViewMode::foveated);
  s.realtime = true;
  // 10 ms: the fixed part of a 160x100 frame (maps, composing) must stay under 60 % of it, or the
  // loop renders smaller and its pixels are no longer the renderer's; with 5 ms it took 3.47 ms in
  // the sanitizer build while another test ran beside it on two cores
  s.frame_budget_ms = 10;
  ViewSession session(box(), box_tracer(), camera, s, fixed({50, 40}));
  session.set_display_refresh_hz(60);
  ASSERT_TRUE(session.wait_until_converged(60, kNone));
  EXPECT_NE(session.status().stage.find("realtime: fovea converged"), std::string::npos) << session.status().stage;
  EXPECT_EQ(session.status().stage.find("frame budget"), std::string::npos) << session.status().stage;  // 10 ms fits 60 Hz
  EXPECT_EQ(session.status().render_gaze, glm::dvec2(50, 40));
  RenderParams p = s.render;
  p.gaze_px = glm::dvec2(50, 40);
  const Frame frame = render_frame(box_tracer(), box(), camera, p);
  const Rgba8 expected = to_rgba8(frame.color);
  ASSERT_EQ(session.image().width, expected.width);
  size_t fovea = 0, same = 0;
  for (size_t i = 0; i < frame.maps.quality.size(); ++i)
    if (frame.maps.quality[i] >= 1.0f && frame.gbuffer.hit(i)) {
      const int x = static_cast<int>(i % 160), y = static_cast<int>(i / 160);
      ++fovea;
      same += session.image().at(x, y)[0] == expected.at(x, y)[0] && session.image().at(x, y)[1] == expected.at(x, y)[1];
    }
  ASSERT_GT(fovea, 100u);
  EXPECT_EQ(same, fovea);
  // Orbiting the camera a little keeps the fovea's rays: the next frame's fovea is mostly converged
  // already (afresh, one 10 ms frame on a few cores gives its pixels their first rounds of the 400)
  session.set_camera(orbit_camera(camera, 0.5));
  session.update(kNone);
  const std::string stage = session.status().stage;
  EXPECT_NE(stage.find("px kept their rays"), std::string::npos) << stage;
  const size_t open = stage.find('(');
  ASSERT_NE(open, std::string::npos) << stage;
  EXPECT_GE(std::stod(stage.substr(open + 1)), 50.0) << stage;
  EXPECT_TRUE(session.wait_until_converged(60, kNone));
}

// --realtime: a budget the still view's fixed part does not fit lowers its size from the view at
// hand, and the stage line says so: the size and why
TEST(ViewSession, ALoweredSizeIsNamedOnTheStageLine) {
  const Camera camera = default_camera(box());
  ViewSettings s = small_settings(ViewMode::foveated);
  s.realtime = true;
  s.frame_budget_ms = 0.01;  // (composing alone takes more)
  ViewSession session(box(), box_tracer(), camera, s, fixed({50, 40}));
  std::string lowered;
  for (int k = 0; k < 30 && lowered.empty(); ++k) {
    session.update(kNone);
    if (const std::string stage = session.status().stage; stage.find("a smaller size from the view at hand") != std::string::npos)
      lowered = stage;
    // the shown image's gaze at the size asked for, the frame that chose the smaller size included
    // (read at its own size, not the next frame's)
    EXPECT_NEAR(session.status().render_gaze.x, 50, 1e-6) << k;
    EXPECT_NEAR(session.status().render_gaze.y, 40, 1e-6) << k;
  }
  ASSERT_FALSE(lowered.empty()) << session.status().stage;
  EXPECT_NE(lowered.find("rendering at"), std::string::npos) << lowered;
  EXPECT_NE(lowered.find("frame budget"), std::string::npos) << lowered;
}

// --realtime --min-scale 1: the size is held, and the stage line says why its frames come late
TEST(ViewSession, ASizeHeldAtMinScaleIsNamedOnTheStageLine) {
  ViewSettings s = small_settings(ViewMode::foveated);
  s.realtime = true;
  s.frame_budget_ms = 0.01;  // (composing alone takes more)
  s.min_scale = 1;
  ViewSession session(box(), box_tracer(), default_camera(box()), s, fixed({50, 40}));
  std::string held;
  for (int k = 0; k < 30 && held.empty(); ++k) {
    session.update(kNone);
    if (const std::string stage = session.status().stage; stage.find("(min_scale): frames come late") != std::string::npos) held = stage;
    EXPECT_EQ(session.status().stage.find("a smaller size"), std::string::npos) << k;
  }
  EXPECT_FALSE(held.empty()) << session.status().stage;
}

// --realtime: a budget longer than the display's refresh makes every frame miss refreshes; the
// stage line says so, where the window knows the refresh
TEST(ViewSession, ABudgetLongerThanTheRefreshIsNamed) {
  ViewSettings s = small_settings(ViewMode::foveated);
  s.realtime = true;
  s.frame_budget_ms = 12;
  ViewSession session(box(), box_tracer(), default_camera(box()), s, fixed({50, 40}));
  session.update(kNone);
  EXPECT_EQ(session.status().stage.find("frame budget"), std::string::npos) << session.status().stage;  // refresh unknown
  session.set_display_refresh_hz(120);
  session.update(kNone);
  EXPECT_NE(session.status().stage.find("the frame budget of 12 ms is longer than the display's refresh (8.33 ms at 120 Hz)"),
            std::string::npos)
      << session.status().stage;
  session.set_display_refresh_hz(60);
  session.update(kNone);
  EXPECT_EQ(session.status().stage.find("frame budget"), std::string::npos) << session.status().stage;
}

TEST(ViewSession, SideBySideShowsFoveatedReferenceAndTheirDifference) {
  const Camera camera = default_camera(box());
  const ViewSettings s = small_settings(ViewMode::side_by_side);
  ViewSession session(box(), box_tracer(), camera, s, fixed({120, 30}));
  EXPECT_EQ(session.panes(), 3);
  ASSERT_TRUE(session.wait_until_converged(120, kNone));
  RenderParams p = s.render;
  p.gaze_px = glm::dvec2(120, 30);
  const Frame foveated = render_frame(box_tracer(), box(), camera, p);
  p.mode = RenderMode::full;
  const Frame reference = render_frame(box_tracer(), box(), camera, p);
  ASSERT_EQ(session.image().width, 3 * s.render.width);
  EXPECT_EQ(differing(session.image(), 0, to_rgba8(foveated.color)), 0u);
  EXPECT_EQ(differing(session.image(), s.render.width, to_rgba8(reference.color)), 0u);
  // The third pane: black where the two agree, brighter where they differ (near the gaze they agree best)
  Image diff(s.render.width, s.render.height, 3);
  for (size_t i = 0; i < diff.pixels.size(); ++i)
    diff.pixels[i] = std::min(1.0f, std::abs(foveated.color.pixels[i] - reference.color.pixels[i]) * s.diff_gain);
  EXPECT_EQ(differing(session.image(), 2 * s.render.width, to_rgba8(diff)), 0u);
}

TEST(ViewSession, VisionModeIsTheSimulationsStep) {
  const Camera camera = default_camera(box());
  ViewSettings s = small_settings(ViewMode::vision);
  s.eye_overrides.pupil_diameter_mm = 8;
  ViewSession session(box(), box_tracer(), camera, s, fixed({40, 50}));
  ASSERT_TRUE(session.wait_until_converged(120, kNone));
  ViewSettings resolved = s;
  resolve(resolved);
  VisionSimulation sim(box_tracer(), box(), resolved.vision);
  const StepStats step = sim.step(camera, glm::vec2(40, 50));
  EXPECT_EQ(differing(session.image(), 0, to_rgba8(sim.perceived())), 0u);
  ASSERT_TRUE(session.status().step.has_value());
  EXPECT_EQ(session.status().step->step, 1);
  EXPECT_DOUBLE_EQ(session.status().step->sharp_fraction, step.sharp_fraction);
  // The sharp-region overlay tints exactly the pixels the field remembers sharp
  Overlays sharp = kNone;
  sharp.sharp = true;
  session.update(sharp);
  const Rgba8& tinted = session.image();
  size_t tinted_px = 0, sharp_px = 0;
  const Rgba8 plain = to_rgba8(sim.perceived());
  for (int y = 0; y < plain.height; ++y)
    for (int x = 0; x < plain.width; ++x) {
      const bool is_sharp = sim.coc_px()[static_cast<size_t>(y) * plain.width + x] < resolved.vision.sharp_px;
      const bool changed = tinted.at(x, y)[1] != plain.at(x, y)[1] || tinted.at(x, y)[0] != plain.at(x, y)[0];
      sharp_px += is_sharp;
      tinted_px += changed;
      if (!is_sharp) EXPECT_FALSE(changed) << x << "," << y;
    }
  EXPECT_GT(sharp_px, 0u);
  EXPECT_GE(tinted_px, sharp_px * 95 / 100);  // a green tint changes almost every sharp pixel
}

TEST(ViewSession, VisionModeShowsTheImpairedEye) {
  // achromatopsia and a field loss through the view: the same pixels as the simulation's step,
  // and grey
  const Camera camera = default_camera(box());
  ViewSettings s = small_settings(ViewMode::vision);
  s.eye = "achromatopsia+field:hemianopia:left+field-view:both";
  ViewSession session(box(), box_tracer(), camera, s, fixed({80, 50}));
  ASSERT_TRUE(session.wait_until_converged(120, kNone));
  ViewSettings resolved = s;
  resolve(resolved);
  ASSERT_TRUE(resolved.vision.impair.any());
  VisionSimulation sim(box_tracer(), box(), resolved.vision);
  sim.step(camera, glm::vec2(80, 50));
  EXPECT_EQ(differing(session.image(), 0, to_rgba8(sim.perceived())), 0u);
  const Rgba8& shown = session.image();
  for (int y = 0; y < shown.height; y += 7)
    for (int x = 0; x < shown.width; x += 7) {
      EXPECT_EQ(shown.at(x, y)[0], shown.at(x, y)[1]);
      EXPECT_EQ(shown.at(x, y)[1], shown.at(x, y)[2]);
    }
}

TEST(ViewSession, MouseRestingBecomesTheFixationTheRenderFollows) {
  const Camera camera = default_camera(box());
  const ViewSettings s = small_settings(ViewMode::foveated);
  GazeInput g;
  const glm::ivec2 size(s.render.width, s.render.height);
  g.source = std::make_unique<MouseSource>(size);
  g.mapping = make_screen_mapping(size, size);
  g.display = s.render.display;
  ViewSession session(box(), box_tracer(), camera, s, std::move(g));
  ASSERT_NE(session.mouse(), nullptr);
  // 60 Hz cursor samples: resting at (30, 30), a quick move, resting at (120, 70)
  double t = 0;
  for (int i = 0; i < 20; ++i, t += 1.0 / 60) session.mouse()->move({30, 30}, t);
  for (int i = 1; i <= 3; ++i, t += 1.0 / 60) session.mouse()->move({30 + 30.0 * i, 30 + 13.3 * i}, t);
  session.update(kNone);
  const auto first = session.status().fixation;
  ASSERT_TRUE(first.has_value());
  EXPECT_NEAR(first->x, 30, 0.5);
  EXPECT_NEAR(first->y, 30, 0.5);
  for (int i = 0; i < 20; ++i, t += 1.0 / 60) session.mouse()->move({120, 70}, t);
  ASSERT_TRUE(session.wait_until_converged(120, kNone));
  EXPECT_NEAR(session.status().render_gaze.x, 120, 0.5);
  EXPECT_NEAR(session.status().render_gaze.y, 70, 0.5);
  // The cursor off the image is a lost sample: the fixation holds
  session.mouse()->move({0, 0}, t, false);
  session.update(kNone);
  EXPECT_FALSE(session.status().gaze.has_value());
  EXPECT_NEAR(session.status().fixation->x, 120, 0.5);
}

TEST(ViewSession, VisionStepsFollowRecordedFixationsAndBlinks) {
  // 500 Hz on a 480×300 screen: 300 ms at (100, 100), a 150 ms blink (lost samples), 300 ms at
  // (400, 200), a 28 ms saccade, 300 ms at (240, 150); replayed on a clock the test advances
  Recording rec;
  rec.source = "three fixations";
  rec.screen_px = {480, 300};
  double t = 0;
  auto hold = [&](glm::dvec2 p, int n, bool valid) {
    for (int i = 0; i < n; ++i, t += 0.002) {
      GazeSample s;
      s.t_s = t;
      s.valid = valid;
      s.px = valid ? p + glm::dvec2(0.3 * std::sin(i), 0.3 * std::cos(i)) : glm::dvec2(NAN);
      rec.samples.push_back(s);
    }
  };
  hold({100, 100}, 150, true);
  hold({}, 75, false);
  hold({400, 200}, 150, true);
  for (int i = 1; i < 15; ++i) hold(glm::mix(glm::dvec2(400, 200), glm::dvec2(240, 150), i / 15.0), 1, true);
  hold({240, 150}, 150, true);
  double now = 0;
  const ViewSettings s = small_settings(ViewMode::vision);
  GazeInput g;
  g.source = std::make_unique<RecordingPlayback>(rec, 1.0, [&now] { return now; });
  g.mapping = make_screen_mapping(rec.screen_px, {s.render.width, s.render.height});
  g.display = s.render.display;
  ViewSession session(box(), box_tracer(), default_camera(box()), s, std::move(g));
  std::vector<StepStats> steps;
  for (; now < 1.3; now += 1.0 / 60) {
    // Each displayed frame: the step for the current fixation finishes before time moves on
    ASSERT_TRUE(session.wait_until_converged(120, kNone));
    const auto step = session.status().step;
    if (step && (steps.empty() || steps.back().step != step->step)) steps.push_back(*step);
  }
  // The image centre until the first fixation, then one step per fixation (the filter refining a
  // fixation's centre is not a new step), and the blink before the second fixation's
  ASSERT_EQ(steps.size(), 4u);
  const double x[4] = {80, 100 / 3.0, 400 / 3.0, 80};
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(steps[k].focus_px.x, x[k], 1.0) << k;
    EXPECT_EQ(steps[k].blink, k == 2) << k;
  }
}

TEST(ViewSession, ScreenshotWritesTheShownImageAndItsStats) {
  const ViewSettings s = small_settings(ViewMode::foveated);
  ViewSession session(box(), box_tracer(), default_camera(box()), s, fixed({80, 50}));
  ASSERT_TRUE(session.wait_until_converged(120, parse_overlays("gaze")));
  const auto dir = std::filesystem::temp_directory_path() / ("foveal_view_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string png = (dir / "shot.png").string();
  session.save_screenshot(png, {{"ui_frame_ms", 16.5}});
  const Image written = load_image(png);
  ASSERT_EQ(written.width, s.render.width);
  const uint8_t* red = session.image().at(80, 50);
  EXPECT_EQ(red[0], 255);  // the gaze cross is in the screenshot
  EXPECT_EQ(red[1], 0);
  EXPECT_NEAR(written.at(80, 50, 0), 1.0f, 1e-6f);
  std::ifstream in((dir / "shot.json").string());
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["settings"]["foveation"]["max_rays"], 24);
  EXPECT_EQ(j["converged"], true);
  EXPECT_EQ(j["ui_frame_ms"], 16.5);
  EXPECT_GT(j["frame"]["ao_rays"].get<uint64_t>(), 0u);
  std::filesystem::remove_all(dir);
}

TEST(ViewSession, BadSettingsAreRefusedWithTheReason) {
  ViewSettings s = small_settings(ViewMode::vision);
  s.eye = "glaucoma:2";  // severity is 0..1
  EXPECT_THROW(resolve(s), Error);
  s = small_settings(ViewMode::foveated);
  s.render.foveation.gamma = 0;
  EXPECT_THROW(resolve(s), Error);
  // Settings of another mode are checked too: a bad value is a mistake whatever the mode
  s = small_settings(ViewMode::foveated);
  s.vision.starvation = -1;
  EXPECT_THROW(resolve(s), Error);
  s = small_settings(ViewMode::vision);
  s.frame_budget_ms = 0;
  EXPECT_THROW(resolve(s), Error);
  // the loop's margin and periphery share (--margin-ms, --periphery-share) reach its settings, checked
  s = small_settings(ViewMode::foveated);
  s.realtime = true;
  s.frame_budget_ms = 8;
  s.margin_ms = 3;
  s.periphery_share = 0.6;
  EXPECT_NO_THROW(resolve(s));
  EXPECT_EQ(view_loop_settings(s).margin_ms, 3.0);
  EXPECT_EQ(view_loop_settings(s).periphery_share, 0.6);
  EXPECT_EQ(view_loop_settings(s).budget_ms, 8.0);
  for (const auto& [margin, share, name] :
       std::vector<std::tuple<double, double, std::string>>{{8, 1, "margin_ms"}, {-1, 1, "margin_ms"}, {2, 0, "periphery_share"}}) {
    s.margin_ms = margin;
    s.periphery_share = share;
    try {
      resolve(s);
      ADD_FAILURE() << name;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(name + ": must be in", 0), 0u) << e.what();
    }
  }
  EXPECT_THROW(parse_view_mode("fullscreen"), Error);
  try {
    parse_overlays("gaze,heat");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("heat"), std::string::npos);
  }
  EXPECT_EQ(to_string(parse_overlays("all")), "gaze,contours,budget,scanpath,sharp");
  EXPECT_EQ(to_string(parse_overlays("none")), "none");
}

// The view on the GPU (`--device cuda`): the finished panes are the GPU renderer's frames and a
// vision step is the GPU simulation's step. Skipped where no GPU is usable.
TEST(Gpu, ViewShowsTheGpusFramesAndVisionSteps) {
  if (!availability().usable) GTEST_SKIP() << "skipped: " << availability().reason;
  const Camera camera = default_camera(box());
  ViewSettings s = small_settings(ViewMode::side_by_side);
  s.cuda = true;
  ViewSession session(box(), box_tracer(), camera, s, fixed({120, 30}));
  ASSERT_TRUE(session.wait_until_converged(120, kNone));
  gpu::Renderer renderer(box());
  RenderParams p = s.render;
  p.gaze_px = glm::dvec2(120, 30);
  const Frame foveated = renderer.render(camera, p);
  p.mode = RenderMode::full;
  const Frame reference = renderer.render(camera, p);
  ASSERT_EQ(session.image().width, 3 * s.render.width);
  EXPECT_EQ(differing(session.image(), 0, to_rgba8(foveated.color)), 0u);
  EXPECT_EQ(differing(session.image(), s.render.width, to_rgba8(reference.color)), 0u);
  EXPECT_EQ(session.status().ao_rays, reference.stats.ao_rays);

  ViewSettings v = small_settings(ViewMode::vision);
  v.eye_overrides.pupil_diameter_mm = 8;
  v.cuda = true;
  ViewSession vision(box(), box_tracer(), camera, v, fixed({40, 50}));
  ASSERT_TRUE(vision.wait_until_converged(120, kNone));
  resolve(v);
  SimulateParams vp = v.vision;
  vp.cuda = true;
  VisionSimulation sim(box_tracer(), box(), vp);
  const StepStats step = sim.step(camera, glm::vec2(40, 50));
  EXPECT_EQ(differing(vision.image(), 0, to_rgba8(sim.perceived())), 0u);
  ASSERT_TRUE(vision.status().step.has_value());
  EXPECT_DOUBLE_EQ(vision.status().step->sharp_fraction, step.sharp_fraction);
}

TEST(Overlays, GridFillIsTheInterpolatedQuality) {
  const FoveationModel model(Display{}, 97, 61, {30, 20}, FoveationParams{});
  const QualityGrid grid(model, 97, 61, 2);
  std::vector<float> q;
  grid.fill(q);
  ASSERT_EQ(q.size(), 97u * 61u);
  for (int y = 0; y < 61; ++y)
    for (int x = 0; x < 97; ++x) ASSERT_NEAR(q[static_cast<size_t>(y) * 97 + x], grid.quality(x + 0.5, y + 0.5), 1e-5f) << x << "," << y;
}

TEST(Overlays, ContoursLieOnTheirQualityLevels) {
  const int w = 320, h = 200;
  const FoveationModel model(Display{}, w, h, {10, 10}, FoveationParams{});
  Rgba8 image(w, h);
  std::fill(image.px.begin(), image.px.end(), uint8_t(0));
  Overlays o = parse_overlays("contours");
  OverlayInputs in;
  in.model = &model;
  draw_overlays(image, 0, 0, w, h, o, in);
  int half = 0, quarter = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = image.at(x, y);
      const double q = model.evaluate(x, y).quality;
      if (p[0] == 255 && p[1] == 140) {  // q = 0.5 (orange); a contour is two pixels wide
        ++half;
        EXPECT_NEAR(q, 0.5, 0.05) << x << "," << y;
      } else if (p[0] == 230 && p[1] == 30) {  // q = 0.25 (red)
        ++quarter;
        EXPECT_NEAR(q, 0.25, 0.03) << x << "," << y;
      }
    }
  EXPECT_GT(half, 100);
  EXPECT_GT(quarter, 100);
}

TEST(Overlays, BudgetHeatMapFollowsTheRayCount) {
  const int w = 200, h = 120;
  const FoveationModel model(Display{}, w, h, {60, 60}, FoveationParams{});
  Rgba8 image(w, h);
  std::fill(image.px.begin(), image.px.end(), uint8_t(0));
  OverlayInputs in;
  in.model = &model;
  draw_overlays(image, 0, 0, w, h, parse_overlays("budget"), in);
  // Over black at half opacity: the heat colour of n(E)/n_max, halved
  for (auto [x, y] : {std::pair{60, 60}, {100, 60}, {190, 10}}) {
    const FoveaSample f = model.evaluate(x, y);
    const glm::u8vec3 c = heat_colour(static_cast<float>(f.rays) / 400.0f);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(image.at(x, y)[k], c[k] * 0.5, 6.0) << x << "," << y;
  }
  EXPECT_GT(heat_colour(1.0f).r, 200);
  EXPECT_LT(heat_colour(0.0f).r, 30);
}

}  // namespace
}  // namespace foveal
