// The deadline loop: frames within budget under a slowed tracer, the fovea first after a gaze jump
// (to its analytic AO on the sphere over the plane), the same frames for the same inputs under the
// model clock whatever the thread count, a lower resolution where the base shading cannot fit, and
// prediction that never leaves the landed fovea worse.
#include "foveal/render/realtime.h"
#include "foveal/render/pull_push.h"

#include "foveal/util/cpu_share.h"
#include "foveal/util/device.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <numeric>
#include <numbers>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <utility>

namespace foveal {
namespace {

using foveal_test::box;
using foveal_test::sphere_plane;

RenderParams loop_params(int width, int height, int max_rays) {
  RenderParams p;
  p.width = width;
  p.height = height;
  p.foveation.max_rays = max_rays;
  return p;
}

LoopSettings model_clock(double rays_per_ms) {
  LoopSettings s;
  s.clock = LoopClock::model;
  s.model_rays_per_ms = rays_per_ms;
  s.model_fixed_ms = 2;
  return s;
}

// V at a point of the plane under the sphere (R = 1 at H = 2, the whole sphere above the horizon):
// the cosine-weighted solid angle of a sphere of angular radius α at θ from the normal is
// sin²α·cos θ, so V = 1 − R²H/D³ with D the distance to the centre.
double plane_visibility(glm::vec3 p) {
  const double d = glm::length(glm::dvec3(p) - glm::dvec3(0, 2, 0));
  return 1.0 - 2.0 / (d * d * d);
}

bool on_plane(const GBuffer& g, size_t i) { return g.hit(i) && std::abs(g.position[i].y) < 1e-3f; }

// The fovea's plane pixels (rays of this view and those kept from views before): each within its
// own error of V = 1 − R²H/D³, and their mean too.
void expect_fovea_at_analytic_ao(const RealtimeLoop& loop) {
  const FoveationMaps& maps = loop.maps();
  const GBuffer& g = loop.gbuffer();
  const bool kept = !loop.kept_cast().empty();
  size_t n = 0;
  double error_sum = 0, variance_sum = 0;
  for (size_t i = 0; i < maps.quality.size(); ++i) {
    if (maps.quality[i] < 1.0f || !on_plane(g, i)) continue;
    const double c = loop.cast()[i] + (kept ? loop.kept_cast()[i] : 0.0), v = (loop.open()[i] + (kept ? loop.kept_open()[i] : 0.0)) / c;
    const double expected = plane_visibility(g.position[i]);
    const double se = std::sqrt(expected * (1 - expected) / c) + 0.5 / c;
    EXPECT_NEAR(v, expected, 5 * se) << "pixel " << i;
    error_sum += v - expected;
    variance_sum += se * se;
    ++n;
  }
  ASSERT_GT(n, 50u);
  EXPECT_LT(std::abs(error_sum / n), 4 * std::sqrt(variance_sum) / n);
}

// The slowest frame of 40 under a tracer four times slower (wall clock, 60 Hz budget).
double slowest_frame_under_slowed_tracer(double budget_ms, uint64_t& rays) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  LoopSettings settings;
  settings.budget_ms = budget_ms;
  settings.slowdown = 4;  // the tracer four times slower
  RealtimeLoop loop(*renderer, box(), loop_params(320, 200, 400), settings);
  loop.frame(box().cameras.front());  // the view's surfaces: traced once, before the trial starts
  double worst = 0;
  for (int k = 0; k < 40; ++k) {
    loop.push_gaze(k / 60.0, glm::dvec2(60 + 5 * k, 100));
    const LoopFrame f = loop.frame(box().cameras.front());
    worst = std::max(worst, f.ms);
    rays += f.rays;
    EXPECT_EQ(f.color.width, loop.params().width);
  }
  return worst;
}

// Timed: run alone by its own ctest entry (RUN_SERIAL, tests/CMakeLists.txt), not among the others.
// The operating system may pause a thread for milliseconds on a shared machine, which no program
// prevents; the loop's own scheduling is judged on the best of five runs (of three, a clean-clone
// CI run on the 2-core VM once had all three a few microseconds over: 17.6706 ms against 17.6667).
TEST(RealtimeLoop, DISABLED_EveryFrameIsDeliveredWithinBudgetUnderASlowedTracer) {
  const double budget = 1000.0 / 60;
  double best = INFINITY;
  uint64_t rays = 0;
  for (int run = 0; run < 5 && best > budget + 1.0; ++run) best = std::min(best, slowest_frame_under_slowed_tracer(budget, rays));
  EXPECT_LE(best, budget + 1.0);
  EXPECT_GT(rays, 0u);
}

// The periphery's rays stop at their share of the frame; the fovea's go on to the deadline. Model
// clock: a frame's rays are its allowance exactly, (share·budget − fixed) × rate for the periphery.
TEST(RealtimeLoop, ThePeripheryStopsAtItsShareOfTheFrameAndTheFoveaGoesOnToTheDeadline) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  const Camera& camera = sphere_plane().cameras.front();
  auto run = [&](double share, uint64_t& fovea_frame_rays, uint64_t& periphery_frame_rays) {
    LoopSettings settings = model_clock(3000);
    settings.periphery_share = share;
    RealtimeLoop loop(*renderer, sphere_plane(), loop_params(200, 125, 400), settings);
    loop.push_gaze(0, glm::dvec2(100, 112));
    fovea_frame_rays = periphery_frame_rays = 0;
    bool fovea_done = false;
    for (int k = 0; k < 60 && periphery_frame_rays == 0; ++k) {
      const LoopFrame f = loop.frame(camera);
      if (!f.fovea_done) fovea_frame_rays = std::max(fovea_frame_rays, f.rays);
      if (fovea_done && f.rays > 0) periphery_frame_rays = f.rays;  // a frame of the periphery alone
      fovea_done = f.fovea_done;
    }
  };
  const double budget = LoopSettings{}.budget_ms;
  const auto allowance = static_cast<uint64_t>((budget - 2) * 3000), periphery = static_cast<uint64_t>((0.6 * budget - 2) * 3000);
  uint64_t fovea_rays = 0, periphery_rays = 0;
  run(0.6, fovea_rays, periphery_rays);
  EXPECT_EQ(fovea_rays, allowance);  // the fovea's frames: to the deadline
  EXPECT_EQ(periphery_rays, periphery);
  run(1.0, fovea_rays, periphery_rays);  // 1: the periphery too goes on to the deadline
  EXPECT_EQ(fovea_rays, allowance);
  EXPECT_EQ(periphery_rays, allowance);
}

// Timed, as the deadline test (its own ctest entry, alone): on the wall clock a frame of the
// periphery alone stops its rays at the share of the budget, one refining the fovea goes on to the
// deadline. Medians over the frames of each kind (the machine may pause a frame).
TEST(RealtimeLoop, DISABLED_OnTheWallClockThePeripheryStopsAtItsShareOfTheFrame) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  LoopSettings settings;
  settings.budget_ms = 30;
  settings.periphery_share = 0.3;
  settings.slowdown = 4;  // rays four times dearer: the periphery has work in every frame
  RealtimeLoop loop(*renderer, box(), loop_params(320, 200, 400), settings);
  const Camera& camera = box().cameras.front();
  loop.push_gaze(0, glm::dvec2(160, 100));
  std::vector<double> fovea_end, periphery_end;
  bool fovea_done = false;
  for (int k = 0; k < 200 && periphery_end.size() < 15; ++k) {
    const LoopFrame f = loop.frame(camera);
    if (k > 0 && !f.fovea_done) fovea_end.push_back(f.rays_end_ms);
    if (fovea_done && f.rays > 0) periphery_end.push_back(f.rays_end_ms);
    fovea_done = f.fovea_done;
  }
  ASSERT_GE(fovea_end.size(), 3u);
  ASSERT_GE(periphery_end.size(), 15u);
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  EXPECT_LT(median(periphery_end), 0.3 * 30 + 1.0);  // 9 ms, and a chunk of rays
  EXPECT_GT(median(fovea_end), 0.3 * 30 + 8.0);      // the deadline: 30 − 2 − composing
}

// The CUDA backend runs the same loop: its variants of these tests skip where there is no GPU.
#define FOVEAL_NEED_GPU() \
  if (!availability().usable) GTEST_SKIP() << "skipped: " << availability().reason

void fovea_reaches_its_analytic_ao_before_the_periphery_gets_a_ray(ComputeDevice device) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), device);
  RenderParams params = loop_params(200, 125, 400);
  RealtimeLoop loop(*renderer, sphere_plane(), params, model_clock(3000));
  const Camera& camera = sphere_plane().cameras.front();
  // Settle on the left, then jump to the plane below the sphere
  loop.push_gaze(0, glm::dvec2(30, 100));
  for (int k = 0; k < 10; ++k) loop.frame(camera);
  loop.push_gaze(0.2, glm::dvec2(100, 112));
  LoopFrame f = loop.frame(camera);
  const std::vector<uint32_t> periphery_at_jump = loop.cast();
  const FoveationMaps maps = loop.maps();
  const GBuffer& g = loop.gbuffer();
  bool periphery_touched = false;
  int frames = 1;
  while (!f.fovea_done && frames < 200) {
    f = loop.frame(camera);
    ++frames;
    for (size_t i = 0; i < maps.quality.size(); ++i)
      if (maps.quality[i] < 1.0f && loop.cast()[i] != periphery_at_jump[i]) periphery_touched = true;
    if (!f.fovea_done) EXPECT_FALSE(periphery_touched) << "frame " << frames;
  }
  ASSERT_TRUE(f.fovea_done) << frames << " frames";
  expect_fovea_at_analytic_ao(loop);
  // Then the periphery fills in
  for (int k = 0; k < 5; ++k) loop.frame(camera);
  uint64_t added = 0;
  for (size_t i = 0; i < maps.quality.size(); ++i)
    if (maps.quality[i] < 1.0f) added += loop.cast()[i] - periphery_at_jump[i];
  EXPECT_GT(added, 0u);
}

TEST(RealtimeLoop, AfterAGazeJumpTheFoveaReachesItsAnalyticAoBeforeThePeripheryGetsARay) {
  fovea_reaches_its_analytic_ao_before_the_periphery_gets_a_ray(ComputeDevice::cpu);
}

TEST(RealtimeLoop, OnTheGpuAfterAGazeJumpTheFoveaReachesItsAnalyticAoBeforeThePeripheryGetsARay) {
  FOVEAL_NEED_GPU();
  fovea_reaches_its_analytic_ao_before_the_periphery_gets_a_ray(ComputeDevice::cuda);
}

// A loop on the sphere over the plane, the gaze on the plane below the sphere, its fovea converged
// for a still camera, then `moves` frames each orbiting the camera 0.5° further. Returns the
// frames after the moves began; `with_rays`: the pixels that had rays before the first move,
// `isolated`: of which those whose eight neighbours had none (the periphery's coarse grid).
std::vector<LoopFrame> orbit_after_convergence(RealtimeLoop& loop, int moves, size_t* with_rays = nullptr, size_t* isolated = nullptr) {
  const Camera& camera = sphere_plane().cameras.front();
  loop.push_gaze(0, glm::dvec2(100, 112));
  LoopFrame f = loop.frame(camera);
  for (int k = 0; k < 200 && !f.fovea_done; ++k) f = loop.frame(camera);
  EXPECT_TRUE(f.fovea_done);
  const std::vector<uint32_t>& cast = loop.cast();
  if (with_rays) *with_rays = static_cast<size_t>(std::count_if(cast.begin(), cast.end(), [](uint32_t c) { return c > 0; }));
  if (isolated) {
    const int w = loop.params().width, h = loop.params().height;
    *isolated = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        bool alone = cast[static_cast<size_t>(y * w + x)] > 0;
        for (int dy = -1; dy <= 1 && alone; ++dy)
          for (int dx = -1; dx <= 1 && alone; ++dx)
            if ((dx != 0 || dy != 0) && x + dx >= 0 && y + dy >= 0 && x + dx < w && y + dy < h)
              alone = cast[static_cast<size_t>((y + dy) * w + x + dx)] == 0;
        *isolated += alone ? 1 : 0;
      }
  }
  std::vector<LoopFrame> out;
  for (int k = 1; k <= moves; ++k) out.push_back(loop.frame(orbit_camera(camera, 0.5 * k)));
  return out;
}

TEST(RealtimeLoop, AMovingCameraKeepsTheAoOfTheSurfacesItStillSees) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  const RenderParams params = loop_params(200, 125, 400);
  RealtimeLoop loop(*renderer, sphere_plane(), params, model_clock(3000));
  size_t with_rays = 0, isolated = 0;
  const std::vector<LoopFrame> moved = orbit_after_convergence(loop, 1, &with_rays, &isolated);
  const LoopFrame& f = moved.front();
  ASSERT_TRUE(f.new_view);
  // Nearly every pixel that had rays kept them, and the fovea is still converged with what it kept.
  // (A pixel alone with rays, of the periphery's coarse grid, lends them bilinearly to up to four
  // pixels of the moved view.)
  ASSERT_GT(with_rays, 1000u);
  EXPECT_GT(f.kept_pixels, with_rays * 9 / 10);
  EXPECT_LE(f.kept_pixels, with_rays * 11 / 10 + 3 * isolated);
  EXPECT_GT(f.fovea_converged, 0.95);
  const GBuffer& g = loop.gbuffer();
  // Kept rays are unbiased: the fovea's plane pixels within their error of V = 1 − R²H/D³ at the
  // points the new view sees, and their mean too
  expect_fovea_at_analytic_ao(loop);
  // Without history the moved view starts afresh: its fovea is far from converged
  LoopSettings fresh = model_clock(3000);
  fresh.keep_history = false;
  RealtimeLoop afresh(*renderer, sphere_plane(), params, fresh);
  const LoopFrame a = orbit_after_convergence(afresh, 1).front();
  EXPECT_EQ(a.kept_pixels, 0u);
  EXPECT_LT(a.fovea_converged, 0.3);
  // reset() forgets: the next view starts afresh too
  loop.reset();
  const LoopFrame r = loop.frame(orbit_camera(sphere_plane().cameras.front(), 0.5));
  EXPECT_EQ(r.kept_pixels, 0u);
}

// Wall clock, a 10 ms budget: the sphere over the plane at 1280x800, whose surfaces take longer
// than the budget on a small machine, the gaze at the centre
constexpr double kRestBudgetMs = 40;
struct LargeWallLoop {
  std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  LoopSettings settings = [] {
    LoopSettings s;
    s.budget_ms = 10;
    return s;
  }();
  RealtimeLoop loop{*renderer, sphere_plane(), loop_params(1280, 800, 16), settings};
  const Camera& camera = sphere_plane().cameras.front();
  LargeWallLoop() { loop.push_gaze(0, glm::dvec2(640, 400)); }
};

// A view taken over at another size: where it holds an estimate of its pixels without rays, it is
// the pull-push of the rays it kept (its own, this frame's, came after), to the bit
void expect_estimate_of_kept_rays(const RealtimeLoop& loop) {
  if (!loop.has_estimate()) return;
  const GBuffer& g = loop.gbuffer();
  const std::vector<float>&cast = loop.kept_cast(), &open = loop.kept_open();
  ASSERT_EQ(cast.size(), g.prim.size());
  PullPush whole;
  whole.pull(g.width, g.height, [&](size_t i) { return std::pair{cast[i] > 0 && g.hit(i), cast[i] > 0 ? open[i] / cast[i] : 0.0f}; });
  ASSERT_TRUE(whole.push());
  size_t differ = 0;
  for (size_t i = 0; i < cast.size(); ++i) differ += whole.estimate(i) != loop.estimate(i) ? 1 : 0;
  EXPECT_EQ(differ, 0u);
}

// A camera that starts to move, its surfaces costlier than the budget, renders its first moved view
// smaller (not the late one at full size, nor after five more late frames), and gets the size back
// once it rests, built over several frames.
TEST(RealtimeLoop, AMovingCameraLowersTheSizeAtOnceAndARestingOneGetsItBack) {
  LargeWallLoop large;
  auto& [renderer, settings, loop, camera] = large;
  const double first_view_ms = loop.frame(camera).ms;  // a view at 1280x800 traced at once
  for (int k = 1; k <= 8; ++k) {
    const LoopFrame f = loop.frame(orbit_camera(camera, 0.5 * k));
    if (k == 1 && first_view_ms > 2 * settings.budget_ms) {  // the view's cost per pixel is known: smaller at once
      EXPECT_LT(f.color.width, 1280) << "the first view took " << first_view_ms << " ms: the first moved one should be smaller";
      EXPECT_FALSE(loop.note().empty());
    }
  }
  if (loop.scale() == 1.0) GTEST_SKIP() << "this machine traces 1280x800 surfaces within the 10 ms budget: nothing to lower";
  const double lowered = loop.scale();
  // At rest, a budget that the smaller view leaves time in on any machine (a sanitizer build's
  // frames at the smaller size took longer than 10 ms, and the view was built a row a frame)
  loop.set_budget_ms(kRestBudgetMs);
  const Camera rest = orbit_camera(camera, 4);
  LoopFrame f;
  int frames = 0, rebuilding = 0, first_rebuilding = -1;
  double rebuilding_max_ms = 0;
  uint64_t estimates_before = 0;
  for (; frames < 400 && loop.scale() == lowered; ++frames) {
    estimates_before = loop.estimates_made();
    f = loop.frame(rest);
    if (!f.rebuilding) continue;
    if (first_rebuilding < 0) first_rebuilding = frames;
    ++rebuilding;
    rebuilding_max_ms = std::max(rebuilding_max_ms, f.rebuild_ms);
    EXPECT_EQ(f.color.width, static_cast<int>(std::lround(1280 * lowered)));  // the smaller view is shown meanwhile
  }
  EXPECT_EQ(loop.scale(), 1.0);
  EXPECT_TRUE(loop.note().empty());
  EXPECT_GE(first_rebuilding * kRestBudgetMs, 500.0);  // after half a second at rest, not before
  // The full-size view took several frames, none of them spending near the cost of tracing it at once
  EXPECT_GT(rebuilding, 1);
  EXPECT_LT(rebuilding_max_ms, 0.75 * first_view_ms) << rebuilding << " frames built it";
  EXPECT_EQ(f.color.width, 1280);
  EXPECT_TRUE(f.new_view);
  EXPECT_GT(f.kept_pixels, 0u);  // the rays of the smaller view carried over
  // and the estimate of its pixels without rays was made while it was built: the frame that took it
  // over made none
  EXPECT_EQ(loop.estimates_made(), estimates_before);
  expect_estimate_of_kept_rays(loop);
  // The view built a few rows at a time is the view's surfaces to the bit
  const GBuffer whole = renderer->surfaces(rest, 1280, 800);
  EXPECT_EQ(loop.gbuffer().prim, whole.prim);
  EXPECT_TRUE(foveal_test::same_bits(loop.gbuffer().depth, whole.depth));
  // Its maps are the model's at the gaze, as a view traced at once gets them
  const FoveationMaps& maps = loop.maps();
  const FoveationMaps model = foveation_maps(loop.params(), glm::dvec2(640, 400));
  size_t differ = 0;
  for (size_t i = 0; i < model.rays.size(); ++i) differ += std::abs(int(maps.rays[i]) - int(model.rays[i])) > 1 ? 1 : 0;
  EXPECT_LT(differ, model.rays.size() / 100);
  f = loop.frame(rest);
  EXPECT_EQ(f.color.width, 1280);
  EXPECT_FALSE(f.rebuilding);
}

TEST(RealtimeLoop, ASizeComingBackIsForgottenWhenTheCameraMovesAgain) {
  LargeWallLoop large;
  auto& [renderer, settings, loop, camera] = large;
  loop.frame(camera);
  for (int k = 1; k <= 4; ++k) loop.frame(orbit_camera(camera, 0.5 * k));
  if (loop.scale() == 1.0) GTEST_SKIP() << "this machine traces 1280x800 surfaces within the 10 ms budget: nothing to lower";
  const double lowered = loop.scale();
  loop.set_budget_ms(kRestBudgetMs);
  int frames = 0;
  for (; frames < 200 && !loop.frame(orbit_camera(camera, 2)).rebuilding; ++frames) {}
  ASSERT_LT(frames, 200) << "no size came back at rest";
  // The camera moves while the view is built: that view is dropped, the moved one is the smaller size
  const LoopFrame moved = loop.frame(orbit_camera(camera, 2.5));
  EXPECT_TRUE(moved.new_view);
  EXPECT_FALSE(moved.rebuilding);
  EXPECT_EQ(loop.scale(), lowered);
  EXPECT_EQ(moved.color.width, static_cast<int>(std::lround(1280 * lowered)));
  // … and the size comes back once it rests again
  for (frames = 0; frames < 400 && loop.scale() == lowered; ++frames) loop.frame(orbit_camera(camera, 2.5));
  EXPECT_EQ(loop.scale(), 1.0);
}

// A renderer that hands every call to another: the tests' wrappers override what they watch or change
class ForwardingRenderer : public FrameRenderer {
 public:
  explicit ForwardingRenderer(FrameRenderer& inner) : inner_(inner) {}
  Frame render(const Camera& camera, const RenderParams& params, const FrameOptions& options) override {
    return inner_.render(camera, params, options);
  }
  void reset_history() override { inner_.reset_history(); }
  uint32_t history_frames() const override { return inner_.history_frames(); }
  uint64_t trace_ao_batch(const AoRayBatch& batch) override { return inner_.trace_ao_batch(batch); }
  void prepare_ao_batches(const GBuffer& surfaces, uint64_t version) override { inner_.prepare_ao_batches(surfaces, version); }
  GBuffer surfaces(const Camera& camera, int width, int height) override { return inner_.surfaces(camera, width, height); }
  GBuffer surfaces_rows(const Camera& camera, int width, int height, int y0, int y1) override {
    return inner_.surfaces_rows(camera, width, height, y0, y1);
  }
  double raw_occlusion_rays_per_ms(std::span<const Ray> rays) override { return inner_.raw_occlusion_rays_per_ms(rays); }
  ComputeDevice device() const override { return inner_.device(); }
  size_t triangles() const override { return inner_.triangles(); }
  double build_ms() const override { return inner_.build_ms(); }
  std::string trace_api() const override { return inner_.trace_api(); }

 protected:
  FrameRenderer& inner_;
};

// A renderer whose first view costs `first_ms` more, as a loop's first view pays its first
// allocations: what a camera that starts to move is sized from says too much.
class FirstViewSlow final : public ForwardingRenderer {
 public:
  FirstViewSlow(FrameRenderer& inner, double first_ms) : ForwardingRenderer(inner), first_ms_(first_ms) {}
  GBuffer surfaces(const Camera& camera, int width, int height) override {
    if (views_++ == 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(first_ms_));
    return inner_.surfaces(camera, width, height);
  }

 private:
  double first_ms_;
  int views_ = 0;
};

// A camera that starts to move is sized from the first view's cost per pixel. Where that said too
// much, the moving camera's cheaper views grow back to the size it had before it moved while it
// still moves (they stayed small until it rested), and the rays of the smaller view carry over.
TEST(RealtimeLoop, AMovingCamerasCheapViewsGrowBackWhileItMoves) {
  // (A budget far above what a frame of this view costs even in a sanitizer build beside other
  // tests on two cores: a step of growth needs a frame whose rays ran out early enough, and at a
  // 100-ms budget there 12 frames once left the view at 87 %, and 40 at 91 %. Frames end when their
  // rays run out, so the budget costs no time.)
  const std::unique_ptr<FrameRenderer> cpu = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  FirstViewSlow renderer(*cpu, 1500);
  LoopSettings settings;
  settings.budget_ms = 300;
  RealtimeLoop loop{renderer, sphere_plane(), loop_params(320, 200, 16), settings};
  const Camera& camera = sphere_plane().cameras.front();
  loop.push_gaze(0, glm::dvec2(160, 100));
  EXPECT_GT(loop.frame(camera).ms, 1500.0);  // the first view
  const LoopFrame first_moved = loop.frame(orbit_camera(camera, 0.5));
  EXPECT_TRUE(first_moved.new_view);
  EXPECT_LT(first_moved.color.width, 160) << "sized from the first view's 1500 ms";
  // Those views cost a few milliseconds: the moving camera gets the size it had before it moved
  // back (at once, or in steps on a busy machine), each grown view with the rays of the one before
  int k = 2;
  for (double before = loop.scale(); k <= 40 && loop.scale() < 1.0; ++k, before = loop.scale()) {
    const LoopFrame f = loop.frame(orbit_camera(camera, 0.5 * k));
    EXPECT_TRUE(f.new_view);
    EXPECT_GT(f.kept_pixels, static_cast<uint64_t>(f.color.width) * static_cast<uint64_t>(f.color.height) / 4)
        << "moving frame " << k << " at " << f.color.width << " wide, " << before;
  }
  EXPECT_EQ(loop.scale(), 1.0) << "after " << k - 1 << " moving frames";
  EXPECT_TRUE(loop.note().empty()) << loop.note();
  const LoopFrame full = loop.frame(orbit_camera(camera, 0.5 * k));
  EXPECT_EQ(full.color.width, 320);
  EXPECT_GT(full.kept_pixels, 10000u);
  // A camera at rest has no smaller size to come back from
  for (int still = 0; still < 40; ++still) EXPECT_FALSE(loop.frame(orbit_camera(camera, 2)).rebuilding);
}

TEST(RealtimeLoop, AnOrbitingCameraGivesTheSameFramesWhateverTheThreadCount) {
  std::vector<std::vector<float>> images[2];
  uint64_t kept = 0;
  for (int threads : {1, 2}) {
    const ThreadScope scope(threads);
    const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
    RealtimeLoop loop(*renderer, sphere_plane(), loop_params(160, 100, 64), model_clock(1500));
    for (const LoopFrame& f : orbit_after_convergence(loop, 6)) {
      images[threads - 1].push_back(f.color.pixels);
      kept += f.kept_pixels;
    }
  }
  EXPECT_GT(kept, 0u);
  ASSERT_EQ(images[0].size(), images[1].size());
  for (size_t k = 0; k < images[0].size(); ++k) EXPECT_TRUE(foveal_test::same_bits(images[0][k], images[1][k])) << "frame " << k;
}

// With `recycle`, each frame's image is handed back once the next is made; `reused` counts the
// frames composed into the image handed back.
std::vector<std::vector<float>> run_frames(int threads, bool predict, bool recycle = false, int* reused = nullptr,
                                           ComputeDevice device = ComputeDevice::cpu) {
  const ThreadScope scope(threads);
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), device);
  LoopSettings settings = model_clock(1500);
  settings.predict = predict;
  RealtimeLoop loop(*renderer, box(), loop_params(160, 100, 64), settings);
  std::vector<std::vector<float>> images;
  double t = 0;
  const float* handed_back = nullptr;
  for (int k = 0; k < 12; ++k) {
    for (int s = 0; s < 16; ++s, t += 0.001) loop.push_gaze(t, glm::dvec2(40 + (k > 5 ? 60 : 0) + 0.01 * s, 50));
    LoopFrame f = loop.frame(box().cameras.front());
    if (reused && handed_back && f.color.pixels.data() == handed_back) ++*reused;
    images.push_back(f.color.pixels);
    if (recycle) {
      handed_back = f.color.pixels.data();
      loop.recycle(std::move(f.color));
    }
  }
  return images;
}

TEST(RealtimeLoop, TheModelClockGivesTheSameFramesWhateverTheThreadCount) {
  const auto a = run_frames(0, true), b = run_frames(0, true), c = run_frames(1, true);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_TRUE(foveal_test::same_bits(a[k], b[k])) << "frame " << k;
    EXPECT_TRUE(foveal_test::same_bits(a[k], c[k])) << "frame " << k << " on one thread";
  }
  EXPECT_NE(a[0], a[11]);  // the frames do change: rays arrive
}

// On the GPU the same inputs give the same frames run after run, and the CPU's frames within the
// Monte-Carlo noise: the rays are the same pixels' same sequences, and only a ray grazing an edge
// can land on the other side of it (the G-buffers differ in their last bits, docs/gpu.md).
TEST(RealtimeLoop, OnTheGpuTheModelClockGivesTheSameFramesAndTheCpus) {
  FOVEAL_NEED_GPU();
  const auto gpu = run_frames(0, true, false, nullptr, ComputeDevice::cuda);
  const auto again = run_frames(1, true, false, nullptr, ComputeDevice::cuda);
  const auto cpu = run_frames(0, true);
  ASSERT_EQ(gpu.size(), cpu.size());
  for (size_t k = 0; k < gpu.size(); ++k) {
    EXPECT_TRUE(foveal_test::same_bits(gpu[k], again[k])) << "frame " << k;
    ASSERT_EQ(gpu[k].size(), cpu[k].size());
    double signed_sum = 0, abs_sum = 0;
    for (size_t i = 0; i < gpu[k].size(); ++i) {
      signed_sum += gpu[k][i] - cpu[k][i];
      abs_sum += std::abs(gpu[k][i] - cpu[k][i]);
    }
    const double n = static_cast<double>(gpu[k].size());
    std::printf("frame %zu: GPU - CPU mean %.2e, mean |GPU - CPU| %.2e\n", k, signed_sum / n, abs_sum / n);
    EXPECT_LT(std::abs(signed_sum / n), 2e-3) << "frame " << k;  // no bias
    EXPECT_LT(abs_sum / n, 0.02) << "frame " << k;               // a few pixels a ray or two apart
  }
  EXPECT_NE(gpu[0], gpu[11]);
}

TEST(RealtimeLoop, AHandedBackImageIsComposedIntoWithTheSameResult) {
  int reused = 0;
  const auto a = run_frames(0, true), b = run_frames(0, true, true, &reused);
  EXPECT_EQ(reused, 11);  // every frame after the first went into the previous one's memory
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k], b[k]) << "frame " << k;
}

TEST(RealtimeLoop, WhereTheBaseShadingCannotFitTheResolutionScalesDownAndSaysSo) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  LoopSettings settings = model_clock(1000);
  settings.model_fixed_ms = 40;  // the base shading alone: 40 ms of a 16.7 ms budget
  RealtimeLoop loop(*renderer, box(), loop_params(320, 200, 64), settings);
  const LoopFrame first = loop.frame(box().cameras.front());
  EXPECT_TRUE(first.late);
  EXPECT_EQ(first.color.width, 320);
  EXPECT_LT(loop.scale(), 1.0);
  EXPECT_NE(loop.note().find("frame budget"), std::string::npos) << loop.note();
  const LoopFrame next = loop.frame(box().cameras.front());
  EXPECT_EQ(next.color.width, loop.params().width);
  EXPECT_LT(next.color.width, 320);
  EXPECT_FALSE(next.late);
}

// A lab whose stimulus must keep its resolution sets the smallest scale to 1: the loop then keeps
// the size asked for whatever its base shading costs, its frames come late, and the note says why
// (and clears once the base shading fits the budget again). Its rays get a quarter of the budget
// after the base shading, so that its AO still refines. A smallest scale of a half stops there
TEST(RealtimeLoop, ASizeHeldByMinScaleIsNotLoweredAndTheNoteSaysItsFramesComeLate) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  const Camera& camera = box().cameras.front();
  LoopSettings settings = model_clock(1000);
  settings.model_fixed_ms = 40;  // the base shading alone: 40 ms of a 16.7 ms budget
  settings.min_scale = 1;
  RealtimeLoop loop(*renderer, box(), loop_params(320, 200, 64), settings);
  for (int k = 0; k < 5; ++k) {
    const LoopFrame f = loop.frame(camera);
    EXPECT_EQ(f.color.width, 320) << "frame " << k;
    EXPECT_TRUE(f.late) << "frame " << k;
    // (the first frame's rays: none, the budget's all the base shading's; then a quarter of it)
    EXPECT_EQ(f.rays, k == 0 ? 0u : static_cast<uint64_t>(kHeldRaysShare * settings.budget_ms * 1000)) << "frame " << k;
  }
  EXPECT_EQ(loop.scale(), 1.0);
  EXPECT_NE(loop.note().find("may not go below 100 % of 320x200 (min_scale): frames come late"), std::string::npos) << loop.note();
  loop.set_budget_ms(100);  // room for it: the note goes
  const LoopFrame roomy = loop.frame(camera);
  EXPECT_FALSE(roomy.late);
  EXPECT_TRUE(loop.note().empty()) << loop.note();

  settings.min_scale = 0.5;
  settings.model_fixed_ms = 80;  // sqrt(0.5 · 16.7 / 80) = 0.32 of the size wanted, 20 ms at a half: held there, late
  RealtimeLoop half(*renderer, box(), loop_params(320, 200, 64), settings);
  half.frame(camera);
  EXPECT_EQ(half.scale(), 0.5);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(half.frame(camera).late);
  EXPECT_EQ(half.scale(), 0.5);
  EXPECT_NE(half.note().find("may not go below 50 %"), std::string::npos) << half.note();
}

// A still view lowered again soon after its size came back waits 600 frames (10 s at 60 Hz) before
// it grows again, then twice as long each time, unless the budget grows by a quarter (a view that
// stayed grown for 600 frames starts afresh): a budget whose
// fixed part sat about the 60 % that lowers the size made it come back and be lowered again every
// few seconds, with a frame or two late each time. The model clock: the fixed part is 10 ms at the
// full size, and scales with the pixels.
TEST(RealtimeLoop, AStillViewLoweredAgainSoonAfterItGrewWaitsLongerBeforeItGrows) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  const Camera& camera = box().cameras.front();
  LoopSettings settings = model_clock(1000);
  settings.model_fixed_ms = 10;
  settings.budget_ms = 20;  // 10 ms of 20: the full size
  RealtimeLoop loop(*renderer, box(), loop_params(160, 100, 16), settings);
  loop.frame(camera);
  ASSERT_EQ(loop.scale(), 1.0);
  // Frames until the scale changes (at most `limit`); how many
  auto until_change = [&](int limit) {
    const double before = loop.scale();
    int k = 0;
    while (k < limit && loop.scale() == before) {
      loop.frame(camera);
      ++k;
    }
    return k;
  };
  const double lowered = std::sqrt(0.5 * 12 / 10.0);  // where 12 ms leaves the fixed part half of it
  loop.set_budget_ms(12);
  ASSERT_LT(until_change(20), 20);
  ASSERT_NEAR(loop.scale(), lowered, 1e-9);
  // The first time, a budget a little larger grows it back at once (to 0.86 of the size, 1.11× 0.77)
  loop.set_budget_ms(14.9);
  ASSERT_LT(until_change(20), 20);
  EXPECT_GT(loop.scale(), lowered);
  // Lowered again soon after (the budget of 12 once more): now held
  loop.set_budget_ms(12);
  ASSERT_LT(until_change(20), 20);
  const int lowered_at = loop.frame_index();
  const double held = loop.scale();
  loop.set_budget_ms(14.9);
  const int waited = until_change(2000);
  EXPECT_GT(loop.scale(), held);
  EXPECT_GE(loop.frame_index() - lowered_at, 590) << "grew after " << waited << " frames";
  EXPECT_LE(loop.frame_index() - lowered_at, 610);
  // And again: twice as long
  loop.set_budget_ms(12);
  ASSERT_LT(until_change(20), 20);
  const int again_at = loop.frame_index();
  loop.set_budget_ms(14.9);
  until_change(3000);
  EXPECT_GE(loop.frame_index() - again_at, 1190);
  EXPECT_LE(loop.frame_index() - again_at, 1210);
  // A budget grown by a quarter or more is no reason to wait
  loop.set_budget_ms(12);
  ASSERT_LT(until_change(20), 20);
  loop.set_budget_ms(15.5);  // 1.29 × 12
  EXPECT_LT(until_change(20), 20);
  // A view that stayed grown for 600 frames was no flap: lowered then, it grows back at once
  for (int k = 0; k < 610; ++k) loop.frame(camera);
  loop.set_budget_ms(12);
  ASSERT_LT(until_change(20), 20);
  loop.set_budget_ms(14.9);
  EXPECT_LT(until_change(20), 20);
}

// A still view made smaller for its fixed part grows back once the budget leaves that part room: at
// once on the model clock (to where it takes half the budget), over a few frames on the wall clock,
// where the larger view is built while the smaller one is shown, none of them late, once the latest
// kBudgetFrames budgets all leave that room
TEST(RealtimeLoop, ASmallerStillViewGrowsBackWhenTheBudgetLeavesItRoom) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  const Camera& camera = box().cameras.front();
  LoopSettings settings = model_clock(1000);
  settings.model_fixed_ms = 40;  // 40 ms of a 16.7 ms budget: sqrt(0.5 · 16.7 / 40) = 0.456 of the size
  RealtimeLoop model(*renderer, box(), loop_params(320, 200, 64), settings);
  model.frame(camera);
  ASSERT_NEAR(model.scale(), std::sqrt(0.5 * settings.budget_ms / 40), 1e-9);
  for (int k = 0; k < 5; ++k) model.frame(camera);
  EXPECT_NEAR(model.scale(), std::sqrt(0.5 * settings.budget_ms / 40), 1e-9);  // the budget as it was: no growth
  EXPECT_TRUE(model.traced_pixels());                                          // (lowered from the view traced at 320x200)
  EXPECT_EQ(model.traced_size(), glm::ivec2(320, 200));
  model.set_budget_ms(40);  // room for 0.707 of it
  model.frame(camera);
  EXPECT_NEAR(model.scale(), std::sqrt(0.5), 1e-9);
  EXPECT_NE(model.note().find("fits the budget again"), std::string::npos) << model.note();
  model.set_budget_ms(100);  // room for the whole, once the 0.707 view has been traced (a frame)
  LoopFrame grown;
  for (int k = 0; k < 3 && model.scale() < 1.0; ++k) grown = model.frame(camera);
  EXPECT_EQ(model.scale(), 1.0);
  EXPECT_TRUE(model.note().empty()) << model.note();
  EXPECT_EQ(model.frame(camera).color.width, 320);
  EXPECT_FALSE(grown.late);
  EXPECT_FALSE(model.traced_pixels());  // (the view traced at the size grown to)
  EXPECT_EQ(model.traced_size(), glm::ivec2(320, 200));

  // The wall clock: a budget of 10 µs lowers the size at once (a still frame's fixed part, composing,
  // takes about 0.08 ms at 320x200); 200 ms brings it back, built over frames
  LoopSettings wall;
  wall.budget_ms = 0.01;
  RealtimeLoop loop(*renderer, box(), loop_params(320, 200, 64), wall);
  int small_budget = 0;  // frames given the 10 µs
  for (; small_budget < 12 && loop.scale() == 1.0; ++small_budget) loop.frame(camera);
  loop.frame(camera);  // (the frame that takes the lower size)
  ++small_budget;
  ASSERT_LT(loop.scale(), 1.0) << "a 10 µs budget did not lower the size";
  const double lowered = loop.scale();
  loop.set_budget_ms(200);
  int frames = 0, rebuilding = 0;
  for (; frames < 400 && loop.scale() == lowered; ++frames) {
    const LoopFrame f = loop.frame(camera);
    rebuilding += f.rebuilding ? 1 : 0;
    EXPECT_FALSE(f.late) << "frame " << frames << ": " << f.ms << " ms";
  }
  EXPECT_EQ(loop.scale(), 1.0) << "after " << frames << " frames";
  EXPECT_FALSE(loop.traced_pixels());  // (built over frames: traced at the size grown to)
  EXPECT_EQ(loop.traced_size(), glm::ivec2(320, 200));
  // The view grows back only once the small budgets have left the latest kBudgetFrames (a budget
  // that swings lowered the size and grew it back every second or so, with late frames each time)
  EXPECT_GE(frames, static_cast<int>(RealtimeLoop::kBudgetFrames) - small_budget);
  EXPECT_GE(rebuilding, 1);
  EXPECT_TRUE(loop.note().empty()) << loop.note();
  EXPECT_EQ(loop.frame(camera).color.width, 320);
}

// A renderer that counts the surfaces it is asked to trace
class SurfaceCounter final : public ForwardingRenderer {
 public:
  using ForwardingRenderer::ForwardingRenderer;
  GBuffer surfaces(const Camera& camera, int width, int height) override {
    ++traced;
    return inner_.surfaces(camera, width, height);
  }
  GBuffer surfaces_rows(const Camera& camera, int width, int height, int y0, int y1) override {
    ++traced;
    return inner_.surfaces_rows(camera, width, height, y0, y1);
  }
  int traced = 0;
};

// A still view's size lowered from the view at hand (`before`, its rays `cast` and `open`, its last
// frame `last_big`): each smaller pixel's source, of the larger pixels nearest to it (its
// footprint), the one with the most rays, else the one nearest its centre — its surface, its rays
// (kept), its colour
void expect_taken_from_view(const RealtimeLoop& loop, const LoopFrame& lowered, const LoopFrame& last_big, const GBuffer& before,
                            const std::vector<uint32_t>& cast, const std::vector<uint32_t>& open) {
  const int big_w = before.width, big_h = before.height;
  const int w = lowered.color.width, h = lowered.color.height;
  ASSERT_EQ(loop.kept_cast().size(), static_cast<size_t>(w) * h);
  auto smaller = [](int b, int big, int small) { return static_cast<int>((b + 0.5) * small / big); };
  std::vector<size_t> sources(static_cast<size_t>(w) * h);
  std::vector<uint8_t> any(sources.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      sources[static_cast<size_t>(y) * w + x] =
          static_cast<size_t>((y + 0.5) * big_h / h) * big_w + static_cast<size_t>((x + 0.5) * big_w / w);
  for (int by = 0; by < big_h; ++by)
    for (int bx = 0; bx < big_w; ++bx) {
      const size_t b = static_cast<size_t>(by) * big_w + bx, i = static_cast<size_t>(smaller(by, big_h, h)) * w + smaller(bx, big_w, w);
      any[i] |= cast[b] > 0 ? 1 : 0;
      if (cast[b] > cast[sources[i]]) sources[i] = b;
    }
  // … and says which: each pixel's pixel of the view before, the view traced last
  EXPECT_EQ(loop.traced_size(), glm::ivec2(big_w, big_h));
  const auto full = loop.traced_pixels();
  ASSERT_TRUE(full);
  ASSERT_EQ(full->size(), sources.size());
  for (size_t i = 0; i < sources.size(); ++i) ASSERT_EQ((*full)[i], sources[i]) << i;
  size_t with_rays = 0, footprints_with_rays = 0, fovea = 0, same_colour = 0;
  double colour_diff = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x, source = sources[i];
      footprints_with_rays += any[i];
      ASSERT_EQ(loop.gbuffer().prim[i], before.prim[source]) << x << "," << y;
      if (!before.hit(source)) continue;
      EXPECT_EQ(loop.gbuffer().position[i], before.position[source]);
      // its rays so far: the larger pixel's, kept (this frame's own under a seed of the new view)
      EXPECT_EQ(loop.kept_cast()[i], static_cast<float>(cast[source])) << x << "," << y;
      EXPECT_EQ(loop.kept_open()[i], static_cast<float>(open[source])) << x << "," << y;
      with_rays += cast[source] > 0 ? 1 : 0;
      double d = 0;
      for (int c = 0; c < 3; ++c) d += std::abs(lowered.color.pixels[i * 3 + c] - last_big.color.pixels[source * 3 + c]);
      colour_diff += d;
      same_colour += d < 1e-5 ? 1 : 0;
      if (loop.maps().quality[i] >= 1.0f) ++fovea;
    }
  EXPECT_EQ(with_rays, footprints_with_rays);  // no footprint's rays lost
  EXPECT_GT(with_rays, static_cast<size_t>(w * h / 2));
  EXPECT_GT(fovea, 100u);
  // The colour: the larger pixel's, but where the blend between AO and the constant term moved
  // with the maps evaluated at the new size (the gaze a fraction of a pixel off at it)
  EXPECT_GT(same_colour, static_cast<size_t>(0.9 * with_rays));
  EXPECT_LT(colour_diff / static_cast<double>(with_rays), 1e-3);
  EXPECT_GT(lowered.fovea_converged, 0.99);
}

// A view lowered twice from `before` (the view traced last): each of its pixels names the one of
// `before` whose surface it shows, a different one each
void expect_traced_pixels(const RealtimeLoop& loop, const GBuffer& before) {
  EXPECT_EQ(loop.traced_size(), glm::ivec2(before.width, before.height));
  const auto full = loop.traced_pixels();
  ASSERT_TRUE(full);
  ASSERT_EQ(full->size(), loop.gbuffer().prim.size());
  for (size_t i = 0; i < full->size(); ++i) {
    ASSERT_LT((*full)[i], before.prim.size());
    ASSERT_EQ(loop.gbuffer().prim[i], before.prim[(*full)[i]]) << i;
    if (before.hit((*full)[i])) ASSERT_EQ(loop.gbuffer().position[i], before.position[(*full)[i]]) << i;
  }
  std::vector<uint32_t> distinct = *full;  // (disjoint footprints: one pixel each)
  std::sort(distinct.begin(), distinct.end());
  EXPECT_EQ(std::adjacent_find(distinct.begin(), distinct.end()), distinct.end());
}

// A still view whose fixed part outgrows the budget (an experiment that leaves the loop less of the
// refresh) is made smaller from the view at hand: no surface traced (traced, that frame was late by
// 34–47 ms at 840×525 on two cores), each smaller pixel one of the larger pixels nearest it — its
// surface point, shading and every ray it had, the one with the most rays — so the image is the
// larger one's, sampled, and no pixel's rays are lost where its footprint had none better
TEST(RealtimeLoop, AStillViewsSizeIsLoweredFromTheViewAtHandWithoutTracingIt) {
  const std::unique_ptr<FrameRenderer> cpu = make_frame_renderer(box(), ComputeDevice::cpu);
  SurfaceCounter renderer(*cpu);
  const Camera& camera = box().cameras.front();
  LoopSettings settings = model_clock(2000);
  settings.model_fixed_ms = 4;
  RealtimeLoop loop(renderer, box(), loop_params(320, 200, 64), settings);
  loop.push_gaze(0.0, glm::dvec2(150, 90));
  LoopFrame big;
  for (int k = 0; k < 60; ++k) big = loop.frame(camera);
  ASSERT_TRUE(big.fovea_done);
  ASSERT_EQ(loop.scale(), 1.0);
  const int traced = renderer.traced;
  ASSERT_TRUE(loop.kept_cast().empty());

  loop.set_budget_ms(5);  // the fixed 4 ms: over 60 % of it
  const LoopFrame last_big = loop.frame(camera);
  ASSERT_EQ(last_big.color.width, 320);
  const GBuffer before = loop.gbuffer();
  const std::vector<uint32_t> cast = loop.cast(), open = loop.open();
  const double scale = loop.scale();
  EXPECT_EQ(last_big.scale, 1.0);  // (the frame's own size: the loop's scale() is the next frame's)
  ASSERT_NEAR(scale, std::sqrt(0.5 * 5 / 4.0), 1e-9);
  EXPECT_NE(loop.note().find("frame budget"), std::string::npos) << loop.note();
  const LoopFrame lowered = loop.frame(camera);
  EXPECT_TRUE(lowered.lowered);
  EXPECT_TRUE(lowered.new_view);
  EXPECT_EQ(lowered.scale, scale);
  EXPECT_EQ(renderer.traced, traced) << "the smaller view was traced";
  const int w = lowered.color.width, h = lowered.color.height;
  EXPECT_EQ(w, static_cast<int>(std::lround(320 * scale)));
  EXPECT_EQ(h, static_cast<int>(std::lround(200 * scale)));
  ASSERT_EQ(loop.kept_cast().size(), static_cast<size_t>(w) * h);

  expect_taken_from_view(loop, lowered, last_big, before, cast, open);
  // and the smaller view goes on: its rays under a seed of its own, no view traced
  for (int k = 0; k < 5; ++k) {
    const LoopFrame f = loop.frame(camera);
    EXPECT_FALSE(f.new_view);
    EXPECT_EQ(f.color.width, w);
  }
  EXPECT_EQ(renderer.traced, traced);
  // Lowered again, from the smaller view: each pixel still names the pixel of the view traced last
  // whose surface it shows (through the first lowering)
  loop.set_budget_ms(3);  // (the fixed part, 4 ms × the pixels' share: over 60 % of it)
  loop.frame(camera);
  const LoopFrame again = loop.frame(camera);
  ASSERT_TRUE(again.lowered);
  ASSERT_LT(again.color.width, w);
  EXPECT_EQ(renderer.traced, traced);
  expect_traced_pixels(loop, before);
  // A camera that moves while a lowering waits traces its view at the lower size
  RealtimeLoop moving(renderer, box(), loop_params(320, 200, 64), settings);
  for (int k = 0; k < 3; ++k) moving.frame(camera);
  moving.set_budget_ms(5);
  moving.frame(camera);
  ASSERT_LT(moving.scale(), 1.0);
  Camera moved = camera;
  moved.eye += glm::vec3(0.05f, 0.0f, 0.0f);
  const int traced_before_move = renderer.traced;
  const LoopFrame f = moving.frame(moved);
  EXPECT_FALSE(f.lowered);
  EXPECT_TRUE(f.new_view);
  EXPECT_EQ(renderer.traced, traced_before_move + 1);
  EXPECT_EQ(f.color.width, static_cast<int>(std::lround(320 * moving.scale())));
  EXPECT_FALSE(moving.traced_pixels());  // (the view traced last itself, at the lower size)
  EXPECT_EQ(moving.traced_size(), glm::ivec2(f.color.width, f.color.height));
}

// On the wall clock, a still view whose frames at the larger size still end in time (their fixed part
// over the 60 % of the budget that lowers the size, but within the budget less its margin) takes the
// smaller size a few rows a frame while the larger one is still shown, by the same rule: taken in one
// frame, it made that frame late by 4–7 ms at a budget of 4 ms (840×525, two cores). One whose
// frames are late anyway takes it at once
TEST(RealtimeLoop, AStillViewWhoseFramesStillFitTakesItsLowerSizeOverFrames) {
  const std::unique_ptr<FrameRenderer> cpu = make_frame_renderer(box(), ComputeDevice::cpu);
  SurfaceCounter renderer(*cpu);
  const Camera& camera = box().cameras.front();
  LoopSettings settings;  // the wall clock
  settings.budget_ms = 100;
  settings.rays_ahead = false;  // (a converged view casts nothing: the rays the view has are those it takes)
  settings.fixed_part_ms = 12;  // 12 ms at full size: over 60 % of 16.7 ms, within the budget
  RealtimeLoop loop(renderer, box(), loop_params(320, 200, 16), settings);
  loop.push_gaze(0.0, glm::dvec2(150, 90));
  LoopFrame big;
  for (int k = 0; k < 2000 && (k < 2 || big.rays > 0); ++k) big = loop.frame(camera);
  ASSERT_EQ(big.rays, 0u) << "the view did not converge";
  ASSERT_EQ(loop.scale(), 1.0);
  const int traced = renderer.traced;
  const GBuffer before = loop.gbuffer();
  const std::vector<uint32_t> cast = loop.cast(), open = loop.open();

  loop.set_budget_ms(1000.0 / 60);
  LoopFrame last_big, f;
  int built_in = 0;  // frames that built the smaller view while the larger one was shown
  for (int k = 0; k < 200 && !f.lowered; ++k) {
    f = loop.frame(camera);
    if (f.lowered) break;
    EXPECT_EQ(f.color.width, 320) << "frame " << k;
    EXPECT_EQ(f.rays, 0u);
    built_in += f.rebuilding ? 1 : 0;
    last_big = f;
  }
  ASSERT_TRUE(f.lowered) << "not lowered";
  EXPECT_TRUE(f.new_view);
  EXPECT_GE(built_in, 1);
  const double scale = std::sqrt(0.5 * (1000.0 / 60) / 12);
  EXPECT_NEAR(loop.scale(), scale, 1e-9);
  EXPECT_NE(loop.note().find("frame budget"), std::string::npos) << loop.note();
  EXPECT_EQ(renderer.traced, traced) << "the smaller view was traced";
  EXPECT_EQ(f.color.width, static_cast<int>(std::lround(320 * scale)));
  EXPECT_EQ(f.color.height, static_cast<int>(std::lround(200 * scale)));
  expect_taken_from_view(loop, f, last_big, before, cast, open);
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(loop.frame(camera).new_view);  // (the smaller view's fixed part fits)
  EXPECT_EQ(renderer.traced, traced);
  // Lowered again over frames, from the smaller view (its fixed part, 12 ms × the pixels' share, over
  // 60 % of 12 ms, within it less the margin): each pixel still names the pixel of the view traced
  // last whose surface it shows, through the first lowering
  loop.set_budget_ms(12);
  int built_again = 0;
  f = LoopFrame();
  for (int k = 0; k < 200 && !f.lowered; ++k) {
    f = loop.frame(camera);
    built_again += f.rebuilding && !f.lowered ? 1 : 0;
  }
  ASSERT_TRUE(f.lowered);
  EXPECT_GE(built_again, 1);
  EXPECT_LT(loop.scale(), scale);
  EXPECT_EQ(renderer.traced, traced);
  expect_traced_pixels(loop, before);

  // The loops below: three frames with room for their fixed part, then 16.7 ms
  const auto start = [&](RealtimeLoop& l) {
    l.push_gaze(0.0, glm::dvec2(150, 90));
    for (int k = 0; k < 3; ++k) l.frame(camera);
    l.set_budget_ms(1000.0 / 60);
  };
  // A view not converged: the smaller view's estimate of its pixels without rays, made from the rays
  // it keeps while it was built, not by the frame that takes it over
  settings.slowdown = 50;  // (few rays a frame: most pixels stay without)
  RealtimeLoop slow(renderer, box(), loop_params(320, 200, 64), settings);
  start(slow);
  uint64_t made = 0;
  f = LoopFrame();
  for (int k = 0; k < 200 && !f.lowered; ++k) {
    made = slow.estimates_made();
    f = slow.frame(camera);
  }
  ASSERT_TRUE(f.lowered);
  EXPECT_EQ(slow.estimates_made(), made);
  ASSERT_TRUE(slow.has_estimate());
  expect_estimate_of_kept_rays(slow);

  // A lower size under way whose larger view's frame comes late for its fixed part (the budget fell
  // meanwhile) is taken at once by the next frame
  settings.slowdown = 1;
  settings.fixed_part_ms = 12;
  settings.rebuild_rows_per_frame = 4;  // (building it takes tens of frames)
  RealtimeLoop fell(renderer, box(), loop_params(320, 200, 16), settings);
  start(fell);
  const int traced_fell = renderer.traced;
  f = LoopFrame();
  for (int k = 0; k < 20 && !f.rebuilding; ++k) f = fell.frame(camera);
  ASSERT_TRUE(f.rebuilding);
  f = fell.frame(camera);
  ASSERT_TRUE(f.rebuilding);  // (still under way)
  fell.set_budget_ms(10);     // 12 ms of fixed part: the frames at the larger size late
  f = fell.frame(camera);
  EXPECT_FALSE(f.lowered);
  EXPECT_EQ(f.color.width, 320);
  f = fell.frame(camera);
  EXPECT_TRUE(f.lowered);
  EXPECT_EQ(f.color.width, static_cast<int>(std::lround(320 * scale)));
  EXPECT_EQ(renderer.traced, traced_fell);

  // A gaze that moves while the view is built: its maps are evaluated again there as its last step,
  // and the frame that takes it over evaluates them at no more than the box around the fovea
  settings.fixed_part_ms = 12;
  settings.rebuild_rows_per_frame = 8;
  RealtimeLoop moved(renderer, box(), loop_params(320, 200, 16), settings);
  start(moved);
  int building = 0;
  f = LoopFrame();
  for (int k = 0; k < 400 && !f.lowered; ++k) {
    if ((building += f.rebuilding ? 1 : 0) == 3) moved.push_gaze(0.5, glm::dvec2(200, 110));  // (about 3°)
    const uint64_t everywhere = moved.maps_everywhere();
    f = moved.frame(camera);
    if (f.lowered) EXPECT_EQ(moved.maps_everywhere(), everywhere);
  }
  ASSERT_TRUE(f.lowered);
  EXPECT_GT(building, 3);
  EXPECT_NEAR(f.gaze_px.x, 200 * moved.scale(), 1e-9);
  settings.rebuild_rows_per_frame.reset();

  // Frames late anyway (a fixed part of 20 ms): the smaller size at the frame after the one that
  // chose it, nothing built before; a fixed part within the budget but not its margin (16 ms) still
  // ends in time, and is built over frames
  for (const double fixed_ms : {20.0, 16.0}) {
    settings.fixed_part_ms = fixed_ms;
    RealtimeLoop late(renderer, box(), loop_params(320, 200, 16), settings);
    start(late);
    int frames = 0, building = 0;
    for (; frames < 200 && !(f = late.frame(camera)).lowered; ++frames) building += f.rebuilding ? 1 : 0;
    EXPECT_TRUE(f.lowered) << fixed_ms;
    if (fixed_ms > 1000.0 / 60) {
      EXPECT_EQ(building, 0);
      EXPECT_LE(frames, 5);  // (five frames judge the fixed part, the three at the larger budget among them)
    } else {
      EXPECT_GE(building, 1);
    }
  }
}

// One frame's pause (a thread descheduled for 66 ms: an 80 ms frame on a shared VM) does not lower
// the resolution for the rest of a run; a sustained fixed part does, within five frames
TEST(RealtimeLoop, OnePausedFrameDoesNotLowerTheResolution) {
  const double budget = 1000.0 / 60;
  FixedPartWindow window;
  bool rescaled = false;
  for (int k = 0; k < 40; ++k) rescaled |= window.add(k == 20 ? 75.0 : 5.5, budget, 5);  // the old mean: 0.7·5.5 + 0.3·75 = 26 ms
  EXPECT_FALSE(rescaled);
  EXPECT_NEAR(window.median_ms(), 5.5, 1e-12);
  window.clear();
  int frames = 0;
  while (!window.add(12.0, budget, 5) && frames < 20) ++frames;  // 12 ms of 16.7: above 60 %
  EXPECT_EQ(frames, 4);                                          // the fifth frame
  window.clear();
  for (double ms : {5.0, 30.0, 5.0, 30.0, 5.0, 5.0}) rescaled |= window.add(ms, budget, 5);
  EXPECT_FALSE(rescaled);                               // two of six frames paused
  EXPECT_FALSE(window.add(30.0, budget, 5));            // three of seven
  EXPECT_TRUE(window.add(30.0, budget, 5));             // four of eight: the median is 17.5 ms
  EXPECT_TRUE(FixedPartWindow().add(40.0, budget, 1));  // the model clock: at once
}

// One sweep of the periphery that a pause lengthened (30 ms where sweeps take 4) stops the sweeps
// only for a while: frames that skip them bring the estimate back within a 12 ms window in well
// under a second; sweeps that always take 20 ms never fit it, however long they are skipped
TEST(RealtimeLoop, OnePausedSweepDoesNotStopThePeripherysRefinement) {
  SweepCost cost;
  for (int k = 0; k < 10; ++k) cost.swept(4.0);
  EXPECT_TRUE(cost.fits(12.0));
  cost.swept(30.0);
  EXPECT_FALSE(cost.fits(12.0));
  int skipped = 0;
  while (!cost.fits(12.0) && skipped < 1000) {
    cost.skipped();
    ++skipped;
  }
  EXPECT_GT(skipped, 5);   // not at once: a pause may last
  EXPECT_LE(skipped, 30);  // half a second at 60 Hz
  EXPECT_GE(cost.estimate_ms(), 4.0);
  cost.swept(4.0);
  EXPECT_TRUE(cost.fits(12.0));

  SweepCost slow;
  for (int k = 0; k < 10; ++k) slow.swept(20.0);
  for (int k = 0; k < 1000; ++k) slow.skipped();
  EXPECT_FALSE(slow.fits(12.0));
  EXPECT_NEAR(slow.estimate_ms(), 20.0, 1e-9);
}

// Before a sweep has been timed its cost is unknown and taken as half the budget, so the first sweep
// waits for a frame with that much left (taken as 1 ms, the first sweep ran up to 2.8 ms past the
// deadline at 840×525); a budget whose frames never leave so much still gets its sweeps; the first
// sweep's own time replaces the guess, which neither a later budget nor frames that skip lower
TEST(RealtimeLoop, TheFirstSweepWaitsForAFrameWithHalfTheBudgetLeft) {
  SweepCost cost;
  cost.set_budget(1000.0 / 60);
  EXPECT_FALSE(cost.timed());
  EXPECT_FALSE(cost.fits(8.0));  // of a 16.7-ms frame
  EXPECT_TRUE(cost.fits(8.5));
  cost.set_budget(1000.0 / 120);  // a new budget before any sweep: half of it
  EXPECT_FALSE(cost.fits(4.1));
  EXPECT_TRUE(cost.fits(4.2));
  int skipped = 0;  // frames that leave 3 ms at most
  while (!cost.fits(3.0) && skipped < 1000) {
    cost.skipped();
    ++skipped;
  }
  EXPECT_GE(skipped, 5);   // 0.95⁷ · 4.17 ms < 3 ms
  EXPECT_LE(skipped, 10);  // within a sixth of a second at 60 Hz
  cost.swept(3.5);
  EXPECT_TRUE(cost.timed());
  EXPECT_DOUBLE_EQ(cost.estimate_ms(), 3.5);
  cost.set_budget(1000.0 / 60);
  EXPECT_DOUBLE_EQ(cost.estimate_ms(), 3.5);
  EXPECT_FALSE(cost.fits(3.4));
  EXPECT_TRUE(cost.fits(3.6));
  cost.scale(2.0);  // a new size: the timed cost scaled, and kept until a sweep at it is timed
  for (int k = 0; k < 100; ++k) cost.skipped();
  EXPECT_DOUBLE_EQ(cost.estimate_ms(), 7.0);
}

// A saccade from `from` to `to` (render pixels) at 1000 Hz, its velocity a symmetric bell over the
// main sequence's duration, then the fixation; pushed up to each frame's time (60 Hz) less 3 ms.
struct SaccadeRun {
  std::vector<double> fovea_error;     // per frame after landing: RMS of V − analytic over the landed fovea's plane pixels
  std::vector<double> converged;       // per frame after landing: the fovea's converged fraction
  int flight_frames = 0;               // frames shown while the saccade flew
  bool measured_after_landing = true;  // every frame after landing placed the fovea at the measured gaze
};

SaccadeRun run_saccade(bool predict, const LandingParams& landing) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  LoopSettings settings = model_clock(2500);
  settings.predict = predict;
  settings.landing = landing;
  RealtimeLoop loop(*renderer, sphere_plane(), loop_params(200, 125, 400), settings);
  const Camera& camera = sphere_plane().cameras.front();
  const glm::dvec2 from(20, 110), to(100, 112);
  const double onset = 0.1, duration = 0.021 + 0.0022 * 20;  // about 20° across this display
  auto position = [&](double t) {
    const double tau = std::clamp((t - onset) / duration, 0.0, 1.0);
    return from + (to - from) * (tau - std::sin(2 * M_PI * tau) / (2 * M_PI));  // a smooth bell of velocity
  };
  SaccadeRun run;
  double t_sample = 0;
  for (int k = 0; k < 40; ++k) {
    const double t_frame = k / 60.0;
    for (; t_sample <= t_frame - 0.003; t_sample += 0.001) loop.push_gaze(t_sample, position(t_sample));
    const LoopFrame f = loop.frame(camera);
    if (t_frame - 0.003 < onset + duration) {
      run.flight_frames += t_frame - 0.003 >= onset ? 1 : 0;
      continue;
    }
    run.measured_after_landing = run.measured_after_landing && !f.predicted && glm::length(f.gaze_px - to) < 0.5;
    // The landed fovea: q = 1 around the true landing
    RenderParams p = loop.params();
    const FoveationMaps landed = foveation_maps(p, to);
    double sum = 0;
    size_t n = 0, done = 0, fovea = 0;
    for (size_t i = 0; i < landed.quality.size(); ++i) {
      if (landed.quality[i] < 1.0f || !loop.gbuffer().hit(i)) continue;
      ++fovea;
      done += loop.cast()[i] >= 400 || loop.converged(i) ? 1 : 0;
      if (!on_plane(loop.gbuffer(), i)) continue;
      const double v = loop.cast()[i] > 0 ? static_cast<double>(loop.open()[i]) / loop.cast()[i] : 1.0;
      const double e = v - plane_visibility(loop.gbuffer().position[i]);
      sum += e * e;
      ++n;
    }
    run.fovea_error.push_back(std::sqrt(sum / std::max<size_t>(n, 1)));
    run.converged.push_back(static_cast<double>(done) / std::max<size_t>(fovea, 1));
    (void)f;
  }
  return run;
}

// A frame's rays rarely cover a predicted fovea: they go to its centre first, the likeliest place of
// the landing (not to its top rows, as pixel order would).
TEST(RealtimeLoop, APredictedFoveaGetsItsRaysFromTheCentreOut) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  LoopSettings settings = model_clock(300);  // ~5,000 rays a frame: a fraction of a fovea's first round
  settings.predict = true;
  RealtimeLoop loop(*renderer, sphere_plane(), loop_params(200, 125, 400), settings);
  const Camera& camera = sphere_plane().cameras.front();
  const glm::dvec2 from(20, 110), to(100, 112);
  const double onset = 0.1, duration = 0.021 + 0.0022 * 20;
  auto position = [&](double t) {
    const double tau = std::clamp((t - onset) / duration, 0.0, 1.0);
    return from + (to - from) * (tau - std::sin(2 * M_PI * tau) / (2 * M_PI));
  };
  double t_sample = 0;
  int checked = 0;
  for (int k = 0; k < 12; ++k) {
    const double t_frame = k / 60.0;
    for (; t_sample <= t_frame - 0.003; t_sample += 0.001) loop.push_gaze(t_sample, position(t_sample));
    const std::vector<uint32_t> before = loop.cast();
    const LoopFrame f = loop.frame(camera);
    if (!f.predicted || before.empty()) continue;
    const FoveationMaps fovea = foveation_maps(loop.params(), f.gaze_px);
    double far_got = 0, near_missed = INFINITY;
    for (size_t i = 0; i < fovea.quality.size(); ++i) {
      if (fovea.quality[i] < 1.0f || !loop.gbuffer().hit(i)) continue;
      const double d = glm::length(glm::dvec2(static_cast<double>(i % 200) + 0.5, static_cast<double>(i / 200) + 0.5) - f.gaze_px);
      if (loop.cast()[i] > before[i])
        far_got = std::max(far_got, d);
      else if (loop.cast()[i] < 400)
        near_missed = std::min(near_missed, d);
    }
    ASSERT_GT(far_got, 0) << "frame " << k << ": no ray in the predicted fovea";
    ASSERT_TRUE(std::isfinite(near_missed)) << "frame " << k << ": the frame covered the whole fovea; the test needs fewer rays";
    // (the maps follow the prediction once it moves 0.1°: the order's centre is within ~2 px)
    EXPECT_LE(far_got, near_missed + 3.0) << "frame " << k;
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

// A frame touches no fresh memory: the rounds' buffers (a sweep's order over every pixel, the
// tasks) are in place once the view is built, a predicted fovea's centre-out order has its own, and
// the view's second frame, composed while the first is shown, has an image made with the view (it
// composed into a fresh one: 1,245 page faults at 840×525, a late frame in bench latency).
// Before, the view's first sweep grew them in its frame (bench latency: 440 page faults in a late
// frame at 840×525), and each predicted fovea swapped the sweep's order for its own small one.
TEST(RealtimeLoop, FramesAfterTheViewTakeNoFreshMemory) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  LoopSettings settings = model_clock(20000);  // the fovea's rays in a frame or two, then sweeps
  settings.predict = true;
  RealtimeLoop loop(*renderer, sphere_plane(), loop_params(840, 525, 16), settings);
  const Camera& camera = sphere_plane().cameras.front();
  const glm::dvec2 from(80, 460), to(420, 470);
  const double onset = 0.1, duration = 0.021 + 0.0022 * 20;
  auto position = [&](double t) {
    const double tau = std::clamp((t - onset) / duration, 0.0, 1.0);
    return from + (to - from) * (tau - std::sin(2 * M_PI * tau) / (2 * M_PI));
  };
  loop.push_gaze(0, from);
  Image shown = loop.frame(camera).color;  // the view; each image is handed back once the next is shown
  // One sweep's order over every pixel: 840 × 525 × 4 bytes, about 430 pages of 4 kB
  const double sweep_pages = 840.0 * 525 * 4 / 4096;
  double t_sample = 0.001;
  int predicted = 0, sweeps = 0;
  for (int k = 1; k < 30; ++k) {
    const double t_frame = k / 60.0;
    for (; t_sample <= t_frame - 0.003; t_sample += 0.001) loop.push_gaze(t_sample, position(t_sample));
    const double before = page_faults();
    LoopFrame f = loop.frame(camera);
    const double faults = page_faults() - before;
    predicted += f.predicted ? 1 : 0;
    sweeps += f.sweeps > 0 ? 1 : 0;
    EXPECT_LT(faults, 0.25 * sweep_pages) << "frame " << k << (f.predicted ? " (predicted)" : "") << ", " << f.sweeps << " sweeps";
    loop.recycle(std::exchange(shown, std::move(f.color)));
  }
  EXPECT_GE(predicted, 1);
  EXPECT_GE(sweeps, 2);
}

// A right prediction leaves the landed fovea better at every frame; a wrong one is abandoned at
// landing (the fovea goes to the measured gaze) and costs at most the flight's rays: its fovea is
// where the one without prediction was at most the flight's frames earlier.
TEST(RealtimeLoop, ARightPredictionHelpsAndAWrongOneIsAbandonedAtLanding) {
  const SaccadeRun without = run_saccade(false, {});
  const SaccadeRun right = run_saccade(true, {});
  LandingParams wild;  // a predictor that overshoots far: its predictions are wrong
  wild.skew = 4;
  wild.max_skew = 4;
  const SaccadeRun wrong = run_saccade(true, wild);
  ASSERT_EQ(without.converged.size(), right.converged.size());
  ASSERT_GT(without.converged.size(), 5u);
  for (size_t k = 0; k < without.converged.size(); ++k) {
    SCOPED_TRACE(::testing::Message() << "frame " << k << " after landing");
    EXPECT_GE(right.converged[k] + 1e-9, without.converged[k]);
    const size_t behind = k >= static_cast<size_t>(wrong.flight_frames) ? k - static_cast<size_t>(wrong.flight_frames) : 0;
    EXPECT_GE(wrong.converged[k] + 1e-9, k >= static_cast<size_t>(wrong.flight_frames) ? without.converged[behind] : 0.0);
  }
  EXPECT_TRUE(right.measured_after_landing);
  EXPECT_TRUE(wrong.measured_after_landing);
  EXPECT_GT(wrong.flight_frames, 0);
  EXPECT_EQ(without.converged.back(), 1.0);
  EXPECT_EQ(wrong.converged.back(), 1.0);
  EXPECT_GT(right.converged[0], without.converged[0]);  // the right one had the fovea's rays ready
  EXPECT_LT(right.fovea_error[0], without.fovea_error[0]);
}

TEST(RealtimeLoop, SamplesTooFarApartForThePredictorAreNamed) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  // 500 Hz samples whose times are given in `unit`s of a second
  auto note_for = [&](double unit, bool predict, int samples) {
    LoopSettings settings = model_clock(2500);
    settings.predict = predict;
    RealtimeLoop loop(*renderer, sphere_plane(), loop_params(200, 125, 400), settings);
    EXPECT_EQ(loop.gaze_sample_hz(), 0.0);
    for (int k = 0; k < samples; ++k) loop.push_gaze(k * 0.002 * unit, glm::dvec2(100 + k % 3, 60));
    EXPECT_NEAR(loop.gaze_sample_hz(), 500 / unit, 1e-6 * 500 / unit);  // the rate the note judges
    return loop.gaze_note();
  };
  EXPECT_EQ(note_for(1, true, 40), "");
  const std::string ms = note_for(1000, true, 40);  // an EyeLink's clock: milliseconds
  EXPECT_NE(ms.find("come 2 s apart"), std::string::npos) << ms;
  EXPECT_NE(ms.find("times in milliseconds"), std::string::npos) << ms;
  const std::string slow = note_for(50, true, 40);  // 10 Hz, in seconds: too slow, and no word of milliseconds
  EXPECT_NE(slow.find("come 0.1 s apart"), std::string::npos) << slow;
  EXPECT_EQ(slow.find("milliseconds"), std::string::npos) << slow;
  // 60 Hz: followed, but a saccade spans a few samples and its landing is predicted too late to gain much
  const std::string late = note_for(1000.0 / 120, true, 40);
  EXPECT_NE(late.find("come 16.7 ms apart (60 Hz)"), std::string::npos) << late;
  EXPECT_NE(late.find("too late to gain much"), std::string::npos) << late;
  EXPECT_EQ(note_for(5, true, 40), "");  // 100 Hz: nothing to say
  EXPECT_EQ(note_for(1000.0 / 120, false, 40), "");
  EXPECT_EQ(note_for(1000, false, 40), "");  // nothing predicted, nothing to say
  EXPECT_EQ(note_for(1000, true, 10), "");   // not before 16 intervals
}

// A trial clock that restarts at 0 (a session's second trial): its samples were all ignored as
// "older than the latest" until the first trial's time came round again, so the loop kept the fovea
// where the first trial left it and predicted nothing, without a word.
TEST(RealtimeLoop, AClockThatGoesBackIsTakenAndNamed) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  LoopSettings settings = model_clock(2500);
  settings.predict = true;
  RealtimeLoop loop(*renderer, sphere_plane(), loop_params(200, 125, 16), settings);
  const Camera& camera = sphere_plane().cameras.front();
  EXPECT_THROW(loop.push_gaze(NAN, glm::dvec2(60, 60)), Error);
  EXPECT_THROW(loop.push_gaze(INFINITY, glm::dvec2(60, 60)), Error);
  for (int k = 0; k <= 1500; ++k) loop.push_gaze(k * 0.001, glm::dvec2(60, 60));  // the first trial: 1.5 s at 1000 Hz
  loop.push_gaze(1.2, glm::dvec2(150, 60));  // a sample out of order: older than what is shown, ignored
  EXPECT_EQ(loop.frame(camera).measured_px, glm::dvec2(60, 60));
  EXPECT_EQ(loop.gaze_note(), "");
  // The second trial's clock starts at 0 again: a 19° saccade from (60, 60) to (150, 60) at 0.1 s
  const glm::dvec2 from(60, 60), to(150, 60);
  const double onset = 0.1, duration = 0.063;
  auto position = [&](double t) {
    const double tau = std::clamp((t - onset) / duration, 0.0, 1.0);
    return from + (to - from) * (tau - std::sin(2 * M_PI * tau) / (2 * M_PI));
  };
  for (int k = 0; k <= 100 + 40; ++k) loop.push_gaze(k * 0.001, position(k * 0.001));  // up to two thirds into the flight
  const LoopFrame flying = loop.frame(camera);
  EXPECT_TRUE(flying.in_flight);
  EXPECT_TRUE(flying.predicted);
  EXPECT_GT(flying.gaze_px.x, flying.measured_px.x);  // ahead of the eye, towards the landing
  EXPECT_GT(flying.measured_px.x, 100);
  const std::string note = loop.gaze_note();
  EXPECT_NE(note.find("clock went back once, the latest time by 1.5 s"), std::string::npos) << note;
  EXPECT_NE(note.find("the landing predictor started afresh"), std::string::npos) << note;
}

TEST(RealtimeLoop, SettingsAreChecked) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  LoopSettings s;
  s.budget_ms = 0;
  EXPECT_THROW(RealtimeLoop(*renderer, box(), loop_params(32, 20, 8), s), Error);
  s = {};
  s.clock = LoopClock::model;  // without a rate
  try {
    RealtimeLoop(*renderer, box(), loop_params(32, 20, 8), s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("model_rays_per_ms"), std::string::npos);
  }
  RenderParams shadows = loop_params(32, 20, 8);
  shadows.shadows = true;
  EXPECT_THROW(RealtimeLoop(*renderer, box(), shadows, {}), Error);
  EXPECT_THROW(parse_loop_clock("sundial"), Error);
  // The margin: unset, the default within a quarter of the budget; given, it must fit in it
  s = {};
  s.budget_ms = 1;
  EXPECT_DOUBLE_EQ(loop_margin_ms(s), 0.25);
  EXPECT_NO_THROW(RealtimeLoop(*renderer, box(), loop_params(32, 20, 8), s));
  s.budget_ms = 1000.0 / 60;
  EXPECT_DOUBLE_EQ(loop_margin_ms(s), kDefaultMarginMs);
  s.margin_ms = 20;
  try {
    RealtimeLoop(*renderer, box(), loop_params(32, 20, 8), s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("margin_ms"), std::string::npos);
  }
  // A budget set later is refused by the setter's own name, and the one before is kept
  s = {};
  RealtimeLoop loop(*renderer, box(), loop_params(32, 20, 8), s);
  for (const double bad : {0.0, -1.0, double(NAN), 1e300}) {
    try {
      loop.set_budget_ms(bad);
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("budget_ms: must be in (0, 10000] ms", 0), 0u) << e.what();
    }
    EXPECT_DOUBLE_EQ(loop.settings().budget_ms, s.budget_ms);
  }
  // A margin given is kept within half of each budget set, from the margin given: one short
  // budget does not shrink it for good (an experiment that sets the budget every flip)
  s.margin_ms = 3;
  RealtimeLoop given(*renderer, box(), loop_params(32, 20, 8), s);
  EXPECT_DOUBLE_EQ(loop_margin_ms(given.settings()), 3);
  given.set_budget_ms(8);
  EXPECT_DOUBLE_EQ(loop_margin_ms(given.settings()), 3);
  given.set_budget_ms(4);
  EXPECT_DOUBLE_EQ(loop_margin_ms(given.settings()), 2);
  given.set_budget_ms(14);
  EXPECT_DOUBLE_EQ(loop_margin_ms(given.settings()), 3);
  EXPECT_DOUBLE_EQ(loop_margin_ms(loop.settings()), kDefaultMarginMs);  // unset: the default, as before
}

}  // namespace
}  // namespace foveal

namespace foveal {
namespace {

// The visibility a frame shows at each pixel, from its colour S + k_a·A: two frames without AO
// give S + ½A and S + A
class VisibilityShown {
 public:
  VisibilityShown(FrameRenderer& renderer, const Camera& camera, RenderParams params, const LoopFrame& frame) : frame_(frame) {
    params.foveation.max_rays = params.foveation.min_rays = 0;
    params.ambient_constant = 0.5f;
    half_ = renderer.render(camera, params, {});
    params.ambient_constant = 1.0f;
    whole_ = renderer.render(camera, params, {});
  }
  double operator()(size_t i) const {
    double best = 0, v = NAN;
    for (size_t c = 0; c < 3; ++c) {
      const double a = whole_.color.pixels[3 * i + c] - half_.color.pixels[3 * i + c];  // ½A
      if (std::abs(a) > best) best = std::abs(a), v = 0.5 + 0.5 * (frame_.color.pixels[3 * i + c] - half_.color.pixels[3 * i + c]) / a;
    }
    return v;
  }

 private:
  const LoopFrame& frame_;
  Frame half_, whole_;
};

// Once every pixel has its n(E) rays (or its τ(E)), the loop's image is the paper's foveated frame
// of the same seed: each pixel's rays are the first of its own sequence. (The loop evaluates the
// foveation model in single precision: where n_max·q² lies within float rounding of a half-integer
// a pixel's n(E) may differ by one ray: under one pixel in a hundred.)
// A pixel the loop has not reached yet shows the visibility of the pixels around it that have rays
// (pull-push, pull_push.h): a weighted mean of theirs, near the analytic AO of the plane under the
// sphere — not the constant ambient term, which left an edge sweeping out through the periphery.
TEST(RealtimeLoop, APixelWithoutRaysYetShowsTheVisibilityOfThePixelsAroundIt) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  const Camera& camera = sphere_plane().cameras.front();
  RenderParams params = loop_params(200, 125, 64);
  params.ambient_constant = 0.5f;
  RealtimeLoop loop(*renderer, sphere_plane(), params, model_clock(3000));  // ~44,000 rays a frame
  loop.push_gaze(0, glm::dvec2(100, 112));
  LoopFrame f;
  // The estimate is made before a frame's rays, every fourth frame once there is one (the 2nd, the
  // 6th): the 6th frame shows one made from the rays of the five before it
  for (int k = 0; k < 5; ++k) f = loop.frame(camera);
  const std::vector<uint32_t> cast = loop.cast(), open = loop.open();
  f = loop.frame(camera);
  const VisibilityShown shown(*renderer, camera, params, f);
  const GBuffer& g = loop.gbuffer();
  const int w = params.width;
  double lo = 1, hi = 0;
  for (size_t i = 0; i < loop.cast().size(); ++i)
    if (cast[i] > 0 && g.hit(i)) lo = std::min(lo, double(open[i]) / cast[i]), hi = std::max(hi, double(open[i]) / cast[i]);
  auto near_rays = [&](size_t i) {
    const int x = static_cast<int>(i) % w, y = static_cast<int>(i) / w;
    for (int dy = -3; dy <= 3; ++dy)
      for (int dx = -3; dx <= 3; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (nx >= 0 && ny >= 0 && nx < w && ny < params.height && cast[static_cast<size_t>(ny * w + nx)] > 0) return true;
      }
    return false;
  };
  size_t without = 0, near = 0;
  double near_error = 0, worst_near = 0, off_constant = 0;
  for (size_t i = 0; i < loop.cast().size(); ++i) {
    if (loop.cast()[i] > 0 || !on_plane(g, i) || loop.maps().rays[i] == 0 || loop.maps().blend[i] < 1.0f) continue;
    const double v = shown(i);
    EXPECT_GE(v, lo - 1e-4) << "pixel " << i;  // a weighted mean of the visibilities measured
    EXPECT_LE(v, hi + 1e-4) << "pixel " << i;
    off_constant += std::abs(v - 0.5);
    ++without;
    if (near_rays(i)) {
      const double e = std::abs(v - plane_visibility(g.position[i]));
      near_error += e;
      worst_near = std::max(worst_near, e);
      ++near;
    }
  }
  ASSERT_GT(without, 1000u) << "the loop reached too much of the image in six frames";
  ASSERT_GT(near, 100u);
  EXPECT_LT(near_error / near, 0.04);  // within 3 px of measured pixels: the plane's AO, near enough
  EXPECT_LT(worst_near, 0.15);
  EXPECT_GT(off_constant / without, 0.3);  // the plane is mostly open (V ≈ 0.9), far from the constant 0.5
}

// Within a fixation the maps follow the gaze in a box around the fovea (3° of effective
// eccentricity beyond its reach, 3.8° here, up and down from the gaze): there they are the model's at
// the gaze, the fovea's pixels among them; outside it they keep the gaze they were last evaluated at
// everywhere until the gaze is half a degree from it. A larger move (a saccade's predicted landing
// among them) evaluates them everywhere.
TEST(RealtimeLoop, WithinAFixationTheMapsFollowTheGazeInABoxAroundTheFovea) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  const Camera& camera = box().cameras.front();
  const RenderParams params = loop_params(420, 262, 64);
  const double ppd = pixels_per_degree(params.display) * params.width / params.display.res_x;
  RealtimeLoop loop(*renderer, box(), params, model_clock(2000));
  // The model's maps at a gaze, and how many pixels' n(E) the loop's differ from them by more than a
  // ray (the loop's are in single precision: n(E) may differ by one) in a set of pixels
  auto differ = [&](const FoveationMaps& maps, glm::dvec2 gaze, auto&& which) {
    const FoveationMaps model = foveation_maps(loop.params(), gaze);
    size_t n = 0, off = 0;
    for (size_t i = 0; i < model.rays.size(); ++i)
      if (which(model, i)) {
        ++n;
        off += std::abs(int(maps.rays[i]) - int(model.rays[i])) > 1 || (maps.quality[i] >= 1.0f) != (model.quality[i] >= 1.0f) ? 1 : 0;
      }
    return std::pair{n, off};
  };
  const auto everywhere = [](const FoveationMaps&, size_t) { return true; };
  const glm::dvec2 start(150, 120);
  loop.push_gaze(0, start);
  loop.frame(camera);
  const FoveationMaps first = loop.maps();
  EXPECT_LT(differ(first, start, everywhere).second, first.rays.size() / 100);
  // A drift of 0.3°: within 5° of it the model's at the new gaze (the fovea among them), beyond 10.5°
  // (outside the box, whose corners reach 9.7°) the first gaze's, to the bit
  const glm::dvec2 drift = start + glm::dvec2(0.3 * ppd, 0.1 * ppd);
  loop.push_gaze(0.1, drift);
  loop.frame(camera);
  const FoveationMaps drifted = loop.maps();
  const auto [near, near_off] = differ(drifted, drift, [](const FoveationMaps& m, size_t i) { return m.eccentricity[i] < 5.0f; });
  EXPECT_GT(near, 5000u);
  EXPECT_LE(near_off, near / 100);
  size_t far = 0, kept = 0;
  const FoveationMaps model = foveation_maps(loop.params(), drift);
  for (size_t i = 0; i < model.rays.size(); ++i)
    if (model.eccentricity[i] > 10.5f) {
      ++far;
      kept +=
          drifted.rays[i] == first.rays[i] && drifted.quality[i] == first.quality[i] && drifted.eccentricity[i] == first.eccentricity[i];
      EXPECT_NEAR(drifted.eccentricity[i], model.eccentricity[i], 0.5) << "pixel " << i;  // a gaze 0.3° off
    }
  EXPECT_GT(far, 10000u);
  EXPECT_EQ(kept, far);
  // The loop's fovea is the model's fovea at the gaze: no pixel outside the box keeps q = 1
  size_t fovea = 0, model_fovea = 0;
  for (size_t i = 0; i < model.quality.size(); ++i) {
    fovea += drifted.quality[i] >= 1.0f;
    model_fovea += model.quality[i] >= 1.0f;
  }
  EXPECT_GT(model_fovea, 1000u);
  EXPECT_NEAR(static_cast<double>(fovea), static_cast<double>(model_fovea), 0.01 * model_fovea);
  // 0.7° from where they were last evaluated everywhere: everywhere again
  const glm::dvec2 moved = start + glm::dvec2(0.7 * ppd, 0);
  loop.push_gaze(0.2, moved);
  loop.frame(camera);
  EXPECT_LT(differ(loop.maps(), moved, everywhere).second, first.rays.size() / 100);
  // A saccade's predicted landings, degrees from where the maps were evaluated everywhere: the
  // model's everywhere
  LoopSettings predicting = model_clock(2000);
  predicting.predict = true;
  RealtimeLoop predicted(*renderer, box(), params, predicting);
  for (int k = 0; k <= 100; ++k) predicted.push_gaze(k * 0.001, start);  // a fixation at 1000 Hz …
  predicted.frame(camera);
  int predicted_frames = 0;
  for (int k = 1; k <= 40; ++k) {  // … then a 10° saccade of 40 ms, with a frame every 8 ms while it flies
    const double tau = k / 40.0;
    predicted.push_gaze(0.1 + k * 0.001,
                        start + glm::dvec2(10 * ppd * (tau - std::sin(2 * std::numbers::pi * tau) / (2 * std::numbers::pi)), 0));
    if (k % 8 != 0) continue;
    const LoopFrame f = predicted.frame(camera);
    if (!f.predicted) continue;
    ++predicted_frames;
    EXPECT_LT(differ(predicted.maps(), f.gaze_px, everywhere).second, first.rays.size() / 100) << "frame at " << k << " ms";
  }
  EXPECT_GT(predicted_frames, 1);
}

// The estimate of the pixels without rays is made again only once a pixel outside the fovea has
// got its first rays (or the maps changed everywhere): while a fovea that follows a fixation's
// drift is refined it would hardly change, and it is a pass over every pixel and a pyramid.
TEST(RealtimeLoop, TheEstimateWaitsWhileOnlyTheFoveaGetsRays) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  const Camera& camera = sphere_plane().cameras.front();
  const RenderParams params = loop_params(200, 125, 64);
  RealtimeLoop loop(*renderer, sphere_plane(), params, model_clock(300));  // ~4,000 rays a frame: the fovea takes many
  const double ppd = pixels_per_degree(params.display) * params.width / params.display.res_x;
  glm::dvec2 gaze(100, 62);
  loop.push_gaze(0, gaze);
  LoopFrame f = loop.frame(camera);  // the view, its grid
  f = loop.frame(camera);            // the first estimate, from the grid's rays
  const uint64_t first = loop.estimates_made();
  ASSERT_GE(first, 1u);
  // A fixation's drift, 0.15° a frame back and forth: the fovea follows, reaching a rim of new
  // pixels, until a frame gives a pixel outside it its first rays (the fovea converged)
  int frames = 0, fovea_rim = 0, outside = 0;
  uint64_t made = 0;
  for (; frames < 60 && !outside; ++frames) {
    gaze.x += (frames % 2 ? -0.15 : 0.15) * ppd;
    const std::vector<uint32_t> before = loop.cast();
    made = loop.estimates_made();
    loop.push_gaze(0.01 * (frames + 1), gaze);
    f = loop.frame(camera);
    for (size_t i = 0; i < before.size(); ++i)
      if (before[i] == 0 && loop.cast()[i] > 0) (loop.maps().quality[i] >= 1.0f ? fovea_rim : outside) += 1;
  }
  ASSERT_GT(outside, 0) << "the fovea did not converge in 60 frames";
  ASSERT_GT(frames, 12) << "the fovea converged too soon to see the estimate wait";
  EXPECT_GT(fovea_rim, 0);  // (the fovea reached new pixels as it followed)
  EXPECT_EQ(made, first);   // no estimate until then (each made before its frame's rays)
  // Then it follows within four frames
  for (int k = 0; k < 5; ++k) loop.frame(camera);
  EXPECT_GT(loop.estimates_made(), first);
}

// On the wall clock an estimate that would pass the frame's rays' deadline waits for a frame with
// room (a frame that evaluated the maps everywhere and made the estimate too was late at a budget
// of 4 ms): its pixels keep the estimate before. A view's first is made at once. The estimate's
// cost is set (test-only) so that the rule, not the machine, decides: a cost no frame has room for,
// and none.
TEST(RealtimeLoop, AnEstimateWithoutRoomBeforeTheDeadlineWaitsForAFrameWithRoom) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  const Camera& camera = sphere_plane().cameras.front();
  const RenderParams params = loop_params(320, 200, 400);  // (pixels left without rays for many frames)
  const double ppd = pixels_per_degree(params.display) * params.width / params.display.res_x;
  struct Run {
    uint64_t first = 0, made = 0;
    int deferred = 0;
  };
  auto run = [&](double cost_ms) {
    LoopSettings settings;  // (the wall clock)
    settings.estimate_cost_ms = cost_ms;
    settings.min_scale = 1;  // (a slow machine's frames lower no size: a new view's first estimate is made at once)
    RealtimeLoop loop(*renderer, sphere_plane(), params, settings);
    Run r;
    glm::dvec2 gaze(40, 62);
    loop.push_gaze(0, gaze);
    // The view, its grid, and its first estimate from the rays (the second frame's, or a later one's
    // where the machine left the first frames no time for rays)
    for (int k = 0; k < 30 && !loop.has_estimate(); ++k) loop.frame(camera);
    EXPECT_TRUE(loop.has_estimate());
    r.first = loop.estimates_made();
    // Saccades of 2° across the view: the maps change everywhere, and pixels outside the fovea get
    // their first rays
    for (int k = 0; k < 40; ++k) {
      gaze.x = 40 + (k / 4 % 5) * 2 * ppd;
      loop.push_gaze(0.02 * (k + 1), gaze);
      const LoopFrame f = loop.frame(camera);
      r.deferred += f.estimate_deferred ? 1 : 0;
    }
    r.made = loop.estimates_made();
    return r;
  };
  const Run none = run(0), never = run(1e6);
  ASSERT_GE(none.first, 1u);
  EXPECT_GT(none.made, none.first + 2);  // made again and again, as due
  EXPECT_LE(none.deferred, 5);           // (only where the machine paused a frame past its deadline before it)
  EXPECT_GE(never.first, 1u);            // the view's first, at once
  EXPECT_EQ(never.made, never.first);    // none since: no frame had room
  EXPECT_GT(never.deferred, 10);         // due, and waiting
}

// A new view's first rays include a coarse grid outside the fovea (every 16th pixel in each
// direction, 64 rays each), so that while the fovea converges the pixels without rays show the
// view's AO measured across it (their estimate, pull-push), not the fovea's carried outwards:
// there the plane under the sphere's analytic AO within 0.03 on average, against 0.2 before. The fovea still gets the
// rest of every frame's rays, and after a gaze jump none of the periphery's (the test above).
TEST(RealtimeLoop, ANewViewsFirstRaysSpanItSoThatItsPixelsWithoutRaysShowItsAo) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(sphere_plane(), ComputeDevice::cpu);
  const Camera& camera = sphere_plane().cameras.front();
  const RenderParams params = loop_params(200, 125, 64);
  RealtimeLoop loop(*renderer, sphere_plane(), params, model_clock(1500));  // ~20,000 rays a frame
  loop.push_gaze(0, glm::dvec2(100, 62));
  LoopFrame f = loop.frame(camera);
  const GBuffer& g = loop.gbuffer();
  const FoveationMaps& maps = loop.maps();
  const int w = params.width;
  size_t grid = 0;
  for (size_t i = 0; i < loop.cast().size(); ++i)
    if (static_cast<int>(i) % w % 16 == 0 && static_cast<int>(i) / w % 16 == 0 && g.hit(i) && maps.rays[i] > 0 && maps.quality[i] < 1.0f) {
      EXPECT_GT(loop.cast()[i], 0u) << "pixel " << i % w << "," << i / w;
      ++grid;
    }
  ASSERT_GT(grid, 50u);
  f = loop.frame(camera);  // the estimate made before its rays, from the first frame's
  ASSERT_FALSE(f.fovea_done) << "the fovea converged too fast to see the periphery meanwhile";
  const VisibilityShown shown(*renderer, camera, params, f);
  std::vector<double> errors;
  for (size_t i = 0; i < loop.cast().size(); ++i) {
    if (loop.cast()[i] > 0 || !on_plane(g, i) || maps.rays[i] == 0 || maps.blend[i] < 1.0f) continue;
    errors.push_back(std::abs(shown(i) - plane_visibility(g.position[i])));
  }
  ASSERT_GT(errors.size(), 10000u);
  // Measured: 0.020 on average, 0.050 at the 95th percentile (from the fovea's pixels alone, as
  // before the grid: 0.199 and 0.292). The worst, 0.42, are plane pixels beside the sphere's silhouette, whose
  // estimate takes in the sphere's measured pixels next to them (the estimate knows no surfaces).
  const double mean = std::accumulate(errors.begin(), errors.end(), 0.0) / static_cast<double>(errors.size());
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(mean, 0.03) << "over " << errors.size() << " plane pixels without rays";
  EXPECT_LT(errors[errors.size() * 95 / 100], 0.08);
}

TEST(RealtimeLoop, AFinishedLoopShowsThePapersFrame) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  RenderParams params = loop_params(160, 100, 64);
  params.reuse.tolerance = 1e-6;  // no early stop: every pixel takes its n(E)
  LoopSettings settings = model_clock(1e6);
  settings.rays_ahead = false;  // (with them, the pixels go on to n_max: below)
  RealtimeLoop loop(*renderer, box(), params, settings);
  loop.push_gaze(0, glm::dvec2(70, 40));
  LoopFrame f;
  for (int k = 0; k < 6; ++k) f = loop.frame(box().cameras.front());
  params.gaze_px = glm::dvec2(70, 40);
  const Frame paper = renderer->render(box().cameras.front(), params, {});
  ASSERT_EQ(f.color.pixels.size(), paper.color.pixels.size());
  size_t differ = 0, same_budget = 0;
  for (size_t i = 0; i < paper.visibility.size(); ++i) {
    double worst = 0;
    for (size_t c = 0; c < 3; ++c) worst = std::max<double>(worst, std::abs(f.color.pixels[3 * i + c] - paper.color.pixels[3 * i + c]));
    if (loop.maps().rays[i] == paper.maps.rays[i]) {
      ++same_budget;
      EXPECT_LT(worst, 1e-4) << "pixel " << i;
    }
    differ += worst >= 1e-4 ? 1 : 0;
  }
  EXPECT_GT(same_budget, paper.visibility.size() * 99 / 100);
  EXPECT_LT(differ, paper.visibility.size() / 100);
}

// A renderer whose next batch has the first chunk of a thread other than the caller's pause for
// `pause` (the machine giving that thread's core to another process)
class PausingRenderer final : public ForwardingRenderer {
 public:
  using ForwardingRenderer::ForwardingRenderer;
  uint64_t trace_ao_batch(const AoRayBatch& batch) override {
    if (!armed) return inner_.trace_ao_batch(batch);
    AoRayBatch b = batch;
    const auto caller = std::this_thread::get_id();
    b.chunk_hook = [this, caller] {
      if (std::this_thread::get_id() != caller && armed.exchange(false)) {
        paused = true;
        std::this_thread::sleep_for(pause);
      }
    };
    return inner_.trace_ao_batch(b);
  }
  std::atomic<bool> armed{false}, paused{false};
  std::chrono::milliseconds pause{300};
};

// On the wall clock a frame does not wait for a thread the machine paused mid-chunk (the loop's
// only late frames on a quiet 2-core VM were such pauses of 2.6–5.6 ms): it returns on time, that
// chunk's rays are dropped and cast again later, and the finished loop still shows the paper's frame.
TEST(RealtimeLoop, AFrameDoesNotWaitForAThreadPausedMidChunk) {
  const std::unique_ptr<FrameRenderer> cpu = make_frame_renderer(box(), ComputeDevice::cpu);
  PausingRenderer renderer(*cpu);
  RenderParams params = loop_params(160, 100, 64);
  params.reuse.tolerance = 1e-6;  // no early stop: every pixel takes its n(E)
  LoopSettings settings;          // the wall clock, 60 Hz
  settings.rays_ahead = false;
  RealtimeLoop loop(renderer, box(), params, settings);
  loop.push_gaze(0, glm::dvec2(70, 40));
  const Camera& camera = box().cameras.front();
  loop.frame(camera);     // the view
  renderer.armed = true;  // (until a thread other than the caller takes a chunk: on a busy machine not always in the first frame)
  // (The machine may pause a thread of its own accord too, on a busy one: each frame says when the
  // frame before left chunks behind, whichever)
  LoopFrame before, paused;
  for (int k = 0; k < 60 && !renderer.paused; ++k) {
    before = paused;
    paused = loop.frame(camera);
  }
  if (!renderer.paused) GTEST_SKIP() << "skipped: no second thread took a chunk (a single core?)";
  EXPECT_LT(paused.ms, 150.0);  // not the 300 ms pause
  EXPECT_GE(paused.chunks_left_behind, 1u);
  EXPECT_EQ(std::isnan(paused.left_behind_ms), before.chunks_left_behind == 0);
  const LoopFrame next = loop.frame(camera);  // waits for that chunk at its start
  // It ended about 300 ms after its pause began, at least 150 ms after the frame's rays stopped
  EXPECT_GT(next.left_behind_ms, 100.0);
  const size_t n = static_cast<size_t>(params.width) * static_cast<size_t>(params.height);
  auto finished = [&] {
    for (size_t i = 0; i < n; ++i)
      if (!loop.converged(i)) return false;
    return true;
  };
  LoopFrame f = next;
  for (int k = 0; k < 2000 && !finished(); ++k) {  // every pixel its n(E)
    const LoopFrame g = loop.frame(camera);
    EXPECT_EQ(std::isnan(g.left_behind_ms), f.chunks_left_behind == 0) << "frame " << g.index;
    f = g;
  }
  ASSERT_TRUE(finished());
  f = loop.frame(camera);
  params.gaze_px = glm::dvec2(70, 40);
  const Frame paper = cpu->render(camera, params, {});
  size_t differ = 0;
  for (size_t i = 0; i < paper.visibility.size(); ++i) {
    if (loop.maps().rays[i] != paper.maps.rays[i]) continue;
    double worst = 0;
    for (size_t c = 0; c < 3; ++c) worst = std::max<double>(worst, std::abs(f.color.pixels[3 * i + c] - paper.color.pixels[3 * i + c]));
    differ += worst >= 1e-4 ? 1 : 0;
  }
  EXPECT_LT(differ, paper.visibility.size() / 100);
}

// A finished image is not swept again (a pass over every pixel that would find nothing to trace)
// until the gaze moves the maps; its frames stay the same meanwhile. With the rays ahead of the gaze
// the image is finished once every pixel has n_max.
TEST(RealtimeLoop, AConvergedImageIsNotSweptAgainUntilTheGazeMoves) {
  for (const bool ahead : {false, true}) {
    SCOPED_TRACE(ahead ? "rays ahead" : "n(E) only");
    const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
    LoopSettings settings = model_clock(1e6);
    settings.rays_ahead = ahead;
    RealtimeLoop loop(*renderer, box(), loop_params(160, 100, 64), settings);
    loop.push_gaze(0, glm::dvec2(70, 40));
    LoopFrame f;
    for (int k = 0; k < 8; ++k) f = loop.frame(box().cameras.front());
    if (ahead)
      for (size_t i = 0; i < loop.cast().size(); ++i)
        if (loop.gbuffer().hit(i)) ASSERT_EQ(loop.cast()[i], 64u) << "pixel " << i;
    ASSERT_EQ(f.rays, 0u);  // finished: nothing left to trace
    const std::vector<float> finished = f.color.pixels;
    for (int k = 0; k < 3; ++k) {
      f = loop.frame(box().cameras.front());
      EXPECT_EQ(f.sweeps, 0u) << "frame " << k;
      EXPECT_TRUE(foveal_test::same_bits(f.color.pixels, finished)) << "frame " << k;
    }
    loop.push_gaze(0.5, glm::dvec2(130, 70));  // the maps follow: a new fovea to refine, then the periphery
    f = loop.frame(box().cameras.front());
    EXPECT_EQ(f.rays > 0, !ahead);  // (with the rays ahead, the new fovea had its n_max already)
    EXPECT_GE(f.sweeps, 1u);
  }
}

// Once every pixel has its n(E), the frames' spare time goes on: every pixel towards n_max, nearest
// the gaze first, within kAheadShare of the budget; where the eye then lands, its fovea is converged
// sooner than without them. No pixel's rays come before the fovea and the periphery have theirs.
TEST(RealtimeLoop, SpareTimeCastsRaysAheadOfTheGazeNearestFirst) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  const Camera& camera = box().cameras.front();
  RenderParams params = loop_params(160, 100, 256);
  const LoopSettings settings = model_clock(20000);  // 126,667 rays a frame ahead: (0.5 × 16.7 ms − 2 ms fixed) × 20,000 / ms
  const uint64_t ahead_allowance = static_cast<uint64_t>((kAheadShare * settings.budget_ms - settings.model_fixed_ms) * 20000);
  LoopSettings without = settings;
  without.rays_ahead = false;
  RealtimeLoop loop(*renderer, box(), params, settings), plain(*renderer, box(), params, without);
  for (RealtimeLoop* l : {&loop, &plain}) l->push_gaze(0, glm::dvec2(40, 30));
  // Both the same until every pixel has its n(E) (the loop without rays ahead casts none then)
  std::vector<uint32_t> before;
  LoopFrame f;
  for (int frames = 0;; ++frames) {
    ASSERT_LT(frames, 400) << "never converged";
    before = loop.cast();
    f = loop.frame(camera);
    if (plain.frame(camera).rays == 0) break;
    ASSERT_EQ(loop.cast(), plain.cast()) << "frame " << frames;
  }
  ASSERT_EQ(before, plain.cast());
  const FoveationMaps& maps = loop.maps();
  // That frame and the next: rays ahead of the gaze, within their share of the budget, nearest first
  for (int k = 0; k < 3; ++k) {
    if (k > 0) {
      before = loop.cast();
      f = loop.frame(camera);
      EXPECT_EQ(plain.frame(camera).rays, 0u);
    }
    EXPECT_GT(f.rays, ahead_allowance / 2) << "frame " << k;
    EXPECT_LE(f.rays, ahead_allowance) << "frame " << k;
    EXPECT_FALSE(f.late);
    // The pixels that got rays are the nearest of those that lacked n_max: none lies a whole degree
    // beyond one left without (the frame's rays went out from the gaze in rings of a degree)
    float nearest_left = 1e9f, farthest_raised = 0;
    size_t raised = 0;
    for (size_t i = 0; i < before.size(); ++i) {
      if (!loop.gbuffer().hit(i)) continue;
      EXPECT_GE(loop.cast()[i], before[i]);
      EXPECT_LE(loop.cast()[i], 256u);
      if (loop.cast()[i] > before[i]) {
        farthest_raised = std::max(farthest_raised, maps.eccentricity[i]);
        ++raised;
      } else if (before[i] < 256u) {
        nearest_left = std::min(nearest_left, maps.eccentricity[i]);
      }
    }
    EXPECT_GT(raised, 100u) << "frame " << k;
    EXPECT_LT(farthest_raised, std::floor(nearest_left) + 1.0f) << "frame " << k;
  }
  // Until every pixel has n_max; then nothing more is traced
  int frames = 0;
  while (loop.frame(camera).rays > 0) ASSERT_LT(++frames, 200) << "the rays ahead never finished";
  for (size_t i = 0; i < loop.cast().size(); ++i)
    if (loop.gbuffer().hit(i)) ASSERT_EQ(loop.cast()[i], 256u) << "pixel " << i;
  EXPECT_EQ(loop.frame(camera).sweeps, 0u);
  // The eye jumps to the image's far corner: its fovea is converged in the first frame, without a
  // ray; the loop without rays ahead traces it afresh
  for (RealtimeLoop* l : {&loop, &plain}) l->push_gaze(1.0, glm::dvec2(140, 85));
  const LoopFrame jumped = loop.frame(camera), fresh = plain.frame(camera);
  EXPECT_TRUE(jumped.fovea_done);
  EXPECT_EQ(jumped.rays, 0u);
  EXPECT_GT(fresh.rays, 10000u);
}

// A sweep's buckets are kept between sweeps and computed again only where a pixel's rays or maps
// changed (sweep_keys.h): through a view's first frames, a fixation's drift (the maps in a box), a
// jump (the maps everywhere), the rays ahead and a new view, every kept bucket is what the pixel's
// state gives now, and the frames are those of a loop that computes every bucket at every sweep
// (the same rays at the same pixels: a loop left to finish shows the paper's frame, below).
TEST(RealtimeLoop, TheSweepsBucketsAreComputedAgainWhereverTheyMayHaveChanged) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  const Camera& camera = box().cameras.front();
  const RenderParams params = loop_params(320, 200, 64);
  const double ppd = pixels_per_degree(params.display) * params.width / params.display.res_x;
  RealtimeLoop loop(*renderer, box(), params, model_clock(4000));  // ~59,000 rays a frame: many sweeps
  glm::dvec2 gaze(100, 80);
  double t = 0;
  uint32_t sweeps = 0;
  auto frames = [&](int count, const char* what) {
    for (int k = 0; k < count; ++k) {
      loop.push_gaze(t += 1.0 / 60, gaze);
      const LoopFrame f = loop.frame(camera);
      sweeps += f.sweeps;
      ASSERT_EQ(loop.sweep_keys_out_of_date(), 0u) << what << ", frame " << k;
    }
  };
  frames(30, "a new view");
  for (int k = 0; k < 6; ++k) {  // a drift of 0.2° a frame and back: the maps in a box
    gaze.x += (k < 3 ? 0.2 : -0.2) * ppd;
    frames(2, "a drift");
  }
  gaze = glm::dvec2(250, 150);  // a jump: the maps everywhere
  frames(40, "after a jump");
  EXPECT_GT(sweeps, 20u);
  // On until the rays ahead (every pixel has its n(E)), and with them: pixels beyond their n(E)
  frames(150, "the rays ahead");
  size_t ahead = 0;
  for (size_t i = 0; i < loop.cast().size(); ++i) ahead += loop.cast()[i] > loop.maps().rays[i];
  EXPECT_GT(ahead, 1000u) << "no rays ahead of the gaze";
  Camera moved = camera;  // a new view, which keeps rays of the one before
  moved.eye += glm::vec3(0.05f, 0, 0);
  loop.push_gaze(t += 1.0 / 60, gaze);
  loop.frame(moved);
  EXPECT_EQ(loop.sweep_keys_out_of_date(), 0u);
  for (int k = 0; k < 10; ++k) {
    loop.push_gaze(t += 1.0 / 60, gaze);
    loop.frame(moved);
    ASSERT_EQ(loop.sweep_keys_out_of_date(), 0u) << "the new view, frame " << k;
  }
}

// Within a fixation the maps change in a box around the fovea. Where every pixel had the rays its
// n(E) asks for, the estimate of the pixels without rays (a pass over every pixel) is made only where
// a pixel of the box now lacks them: not at each drift, but where n(E) reaches 0 inside the box
// (γ = 12: q^γ < 1/128 at q < 0.67; the box's edge is at q ≈ 0.6), and then the drift moves that edge
TEST(RealtimeLoop, ADriftMakesAnEstimateOnlyWherePixelsOfItsBoxLackRays) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  const Camera& camera = box().cameras.front();
  auto estimates_at_drifts = [&](double gamma) {
    RenderParams params = loop_params(320, 200, 64);
    params.foveation.gamma = gamma;
    const double ppd = pixels_per_degree(params.display) * params.width / params.display.res_x;
    LoopSettings settings = model_clock(4000);
    settings.rays_ahead = false;  // (else every pixel goes on to n_max, and none lacks rays)
    RealtimeLoop loop(*renderer, box(), params, settings);
    glm::dvec2 gaze(160, 100);
    double t = 0;
    LoopFrame f;
    for (int k = 0; k < 300 && (k < 2 || f.rays > 0); ++k) {
      loop.push_gaze(t += 1.0 / 60, gaze);
      f = loop.frame(camera);
    }
    EXPECT_EQ(f.rays, 0u) << "the view did not converge";
    int made = 0;
    for (int k = 0; k < 4; ++k) {  // 0.2° a frame, and back: within kMapsStaleDeg of where they were evaluated everywhere
      gaze.x += (k < 2 ? 0.2 : -0.2) * ppd;
      loop.push_gaze(t += 1.0 / 60, gaze);
      const uint64_t before = loop.estimates_made(), everywhere = loop.maps_everywhere();
      f = loop.frame(camera);
      EXPECT_EQ(loop.maps_everywhere(), everywhere) << "γ " << gamma << ", drift " << k << ": the maps everywhere";
      made += loop.estimates_made() > before ? 1 : 0;
    }
    return made;
  };
  EXPECT_EQ(estimates_at_drifts(2), 0);   // n(E) > 0 throughout the box: no pixel of it lacks rays
  EXPECT_GE(estimates_at_drifts(12), 1);  // the edge of n(E) > 0 moves with the drift, within the box
}

// A frame that traces a new view casts no rays ahead of the gaze: a moving camera's frames are the
// same with them and without, even where each view converges within its frame (the frame that finds
// every pixel converged ends its rays there, and the next is another view).
TEST(RealtimeLoop, AMovingCamerasFramesCastNoRaysAhead) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  const Camera& camera = box().cameras.front();
  const RenderParams params = loop_params(84, 52, 16);
  LoopSettings settings = model_clock(1e6);  // every view converges within its frame, with time to spare
  LoopSettings without = settings;
  without.rays_ahead = false;
  RealtimeLoop loop(*renderer, box(), params, settings), plain(*renderer, box(), params, without);
  for (RealtimeLoop* l : {&loop, &plain}) l->push_gaze(0, glm::dvec2(30, 20));
  for (int k = 1; k <= 6; ++k) {
    const LoopFrame a = loop.frame(orbit_camera(camera, 0.5 * k)), b = plain.frame(orbit_camera(camera, 0.5 * k));
    ASSERT_TRUE(a.new_view) << "frame " << k;
    EXPECT_EQ(a.rays, b.rays) << "frame " << k;
    EXPECT_EQ(loop.cast(), plain.cast()) << "frame " << k;
  }
  // At rest the next frame is no new view: its spare time goes ahead
  const LoopFrame still = loop.frame(orbit_camera(camera, 3.0));
  EXPECT_FALSE(still.new_view);
  EXPECT_GT(still.rays, plain.frame(orbit_camera(camera, 3.0)).rays);
}

}  // namespace
}  // namespace foveal

namespace foveal {
namespace {

// Where a frame's time goes at the papers' size (run by hand: --gtest_also_run_disabled_tests).
TEST(RealtimeLoop, DISABLED_TimeOfTheFixedPartsAt840x525) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(box(), ComputeDevice::cpu);
  RealtimeLoop loop(*renderer, box(), loop_params(840, 525, 400), {});
  loop.frame(box().cameras.front());
  for (int k = 0; k < 30; ++k) {
    loop.push_gaze(k / 60.0, glm::dvec2(300 + 0.7 * k, 200));
    const LoopFrame f = loop.frame(box().cameras.front());
    std::printf("frame %d: %.2f ms: maps %.2f plan %.2f trace %.2f compose %.2f; rays %llu scale %.2f\n", k, f.ms, f.maps_ms, f.plan_ms,
                f.trace_ms, f.compose_ms, static_cast<unsigned long long>(f.rays), loop.scale());
  }
}

}  // namespace
}  // namespace foveal
