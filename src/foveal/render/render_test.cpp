// Tests of the renderer: analytic AO, the bit-identical fovea, and thread-count independence.
#include "foveal/render/render.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

using namespace foveal;

namespace {

using foveal_test::box;
using foveal_test::sphere_plane;

RenderParams small_params(RenderMode mode) {
  RenderParams p;
  p.width = 160;
  p.height = 100;
  p.mode = mode;
  p.foveation.max_rays = 24;
  p.gaze_px = glm::dvec2(50, 40);
  return p;
}

using foveal_test::same_bits;

}  // namespace

TEST(AmbientOcclusion, SphereOverPlaneMatchesOneMinusRSquaredOverHSquared) {
  // R = 1 at height H = 2 over an infinite plane, infinite AO distance: V = 1 − (R/H)² = 0.75
  const Tracer tracer(sphere_plane());
  const float eps = surface_epsilon(sphere_plane().bounds());
  const int rays = 400, pixels = 64;
  double sum = 0;
  for (int i = 0; i < pixels; ++i) sum += estimate_visibility(tracer, {0, 0, 0}, {0, 1, 0}, rays, INFINITY, eps, 7, i, 3);
  const double mean = sum / pixels, expected = 0.75;
  // Monte-Carlo error of plain sampling for this count (the Sobol sequence does better)
  const double sigma = std::sqrt(expected * (1 - expected) / (rays * pixels));
  EXPECT_NEAR(mean, expected, 4 * sigma);
  // Each pixel on its own, within the error of its 400 rays
  const float one = estimate_visibility(tracer, {0, 0, 0}, {0, 1, 0}, rays, INFINITY, eps, 1, 0, 0);
  EXPECT_NEAR(one, expected, 4 * std::sqrt(expected * (1 - expected) / rays));
}

TEST(AmbientOcclusion, ConvergesAsRaysGrow) {
  const Tracer tracer(sphere_plane());
  const float eps = surface_epsilon(sphere_plane().bounds());
  double previous_error = 1;
  for (int rays : {7, 97, 4001}) {
    double err = 0;
    for (int i = 0; i < 16; ++i) err += std::abs(estimate_visibility(tracer, {0, 0, 0}, {0, 1, 0}, rays, INFINITY, eps, 3, i, 0) - 0.75);
    err /= 16;
    EXPECT_LT(err, previous_error);
    previous_error = err;
  }
  EXPECT_LT(previous_error, 0.003);
}

TEST(AmbientOcclusion, OpenPlaneIsFullyVisible) {
  const Scene plane = make_builtin_scene("plane");
  const Tracer tracer(plane);
  EXPECT_EQ(estimate_visibility(tracer, {3, 0, -2}, {0, 1, 0}, 400, INFINITY, surface_epsilon(plane.bounds()), 1, 0, 0), 1.0f);
  // Through the renderer: every hit pixel's V is exactly 1
  RenderParams p = small_params(RenderMode::full);
  const Frame f = render_frame(tracer, plane, plane.cameras.front(), p);
  size_t hits = 0;
  for (size_t i = 0; i < f.visibility.size(); ++i)
    if (f.gbuffer.hit(i)) {
      ++hits;
      EXPECT_EQ(f.visibility[i], 1.0f);
    }
  EXPECT_GT(hits, 1000u);
}

TEST(AmbientOcclusion, MaximumDistanceCutsOcclusion) {
  // The sphere's lowest point is 1 above the plane: rays shorter than that see nothing
  const Tracer tracer(sphere_plane());
  const float eps = surface_epsilon(sphere_plane().bounds());
  EXPECT_EQ(estimate_visibility(tracer, {0, 0, 0}, {0, 1, 0}, 256, 0.9f, eps, 1, 0, 0), 1.0f);
  EXPECT_LT(estimate_visibility(tracer, {0, 0, 0}, {0, 1, 0}, 256, 10.0f, eps, 1, 0, 0), 0.9f);
}

// A view that cannot be built is an error naming the camera, never rays that are not finite (which
// abort the process in Embree): an eye too far for single precision, eye and look equal
TEST(Render, ACameraWithNoViewIsRefused) {
  Camera far;
  far.name = "far";
  far.eye = {1e30f, 0, 0};
  try {
    CameraRays rays(far, 16, 10);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("camera 'far': no view from eye (1e+30, 0, 0)"), std::string::npos) << e.what();
  }
  Camera same;
  same.look = same.eye;
  EXPECT_THROW(CameraRays(same, 16, 10), Error);
  Camera distant;
  distant.eye = {1e15f, 0, 0};
  EXPECT_NO_THROW(CameraRays(distant, 16, 10));
}

TEST(Render, FoveaIsBitIdenticalToTheFullFrameReference) {
  const Tracer tracer(box());
  const Camera cam = box().cameras.front();
  const Frame full = render_frame(tracer, box(), cam, small_params(RenderMode::full));
  const Frame fov = render_frame(tracer, box(), cam, small_params(RenderMode::foveated));
  size_t fovea = 0, periphery_differs = 0;
  for (size_t i = 0; i < fov.maps.quality.size(); ++i) {
    if (fov.maps.quality[i] >= 1.0f) {
      ++fovea;
      EXPECT_EQ(fov.maps.rays[i], 24);
      EXPECT_EQ(std::memcmp(&fov.color.pixels[3 * i], &full.color.pixels[3 * i], 3 * sizeof(float)), 0) << "pixel " << i;
      EXPECT_EQ(std::memcmp(&fov.visibility[i], &full.visibility[i], sizeof(float)), 0);
    } else if (fov.gbuffer.hit(i) && fov.color.pixels[3 * i] != full.color.pixels[3 * i]) {
      ++periphery_differs;
    }
  }
  EXPECT_GT(fovea, 100u);
  EXPECT_GT(periphery_differs, 1000u);  // and the periphery really is cheaper and different
  EXPECT_LT(fov.stats.ao_rays, full.stats.ao_rays / 2);
}

TEST(Render, SameImageForAnyThreadCount) {
  const Tracer tracer(box());
  const Camera cam = box().cameras.front();
  RenderParams p = small_params(RenderMode::foveated);
  p.ambient_constant.reset();  // auto: also deterministic
  Frame reference;
  {
    const ThreadScope one(1);
    reference = render_frame(tracer, box(), cam, p);
  }
  for (int threads : {2, 3, 8}) {
    const ThreadScope scope(threads);
    const Frame f = render_frame(tracer, box(), cam, p);
    EXPECT_TRUE(same_bits(f.color.pixels, reference.color.pixels)) << threads << " threads";
    EXPECT_TRUE(same_bits(f.visibility, reference.visibility)) << threads << " threads";
    EXPECT_EQ(f.stats.ao_rays, reference.stats.ao_rays);
  }
  // A different seed changes the noise
  p.seed = 2;
  const Frame other = render_frame(tracer, box(), cam, p);
  EXPECT_FALSE(same_bits(other.visibility, reference.visibility));
}

TEST(Render, GazeAnywhereIncludingOffTheImage) {
  const Tracer tracer(box());
  const Camera cam = box().cameras.front();
  uint64_t previous = 0;
  for (glm::dvec2 gaze : {glm::dvec2(80, 50), glm::dvec2(0, 0), glm::dvec2(159.9, 99.9), glm::dvec2(-400, 300)}) {
    RenderParams p = small_params(RenderMode::foveated);
    p.gaze_px = gaze;
    const Frame f = render_frame(tracer, box(), cam, p);
    for (float v : f.color.pixels) ASSERT_TRUE(std::isfinite(v));
    EXPECT_GT(f.stats.ao_rays, 0u);
    if (previous) EXPECT_LT(f.stats.ao_rays, previous);  // each further away than the last
    previous = f.stats.ao_rays;
  }
}

TEST(Render, BlendUsesTheAmbientConstantAwayFromTheGaze) {
  // k_a = b·V + (1 − b)·k_const: changing k_const changes a pixel by (1 − b)·Δk·i_a·albedo exactly
  const Scene plane = make_builtin_scene("plane");
  const Tracer tracer(plane);
  RenderParams p = small_params(RenderMode::foveated);
  p.foveation.beta = 4;
  p.ambient_constant = 0.0f;
  const Frame dark = render_frame(tracer, plane, plane.cameras.front(), p);
  p.ambient_constant = 0.5f;
  const Frame bright = render_frame(tracer, plane, plane.cameras.front(), p);
  const size_t gaze = 40 * 160 + 50, far = 99 * 160 + 159;
  ASSERT_TRUE(dark.gbuffer.hit(gaze));
  ASSERT_TRUE(dark.gbuffer.hit(far));
  EXPECT_EQ(dark.maps.blend[gaze], 1.0f);
  EXPECT_EQ(bright.color.pixels[3 * gaze], dark.color.pixels[3 * gaze]);  // b = 1: k_const unused
  const float b = dark.maps.blend[far];
  EXPECT_GT(b, 0.0f);
  EXPECT_LT(b, 0.5f);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(bright.color.pixels[3 * far + c] - dark.color.pixels[3 * far + c],
                (1 - b) * 0.5f * plane.ambient[c] * dark.gbuffer.albedo[far][c], 1e-5f);
}

TEST(Render, RejectsBadParameters) {
  RenderParams p;
  p.width = 0;
  EXPECT_THROW(validate(p), Error);
  p = RenderParams{};
  p.foveation.min_rays = 500;
  EXPECT_THROW(validate(p), Error);
  p = RenderParams{};
  p.foveation.gamma = 0;
  EXPECT_THROW(validate(p), Error);
  p = RenderParams{};
  p.ao_distance = -1.0f;
  EXPECT_THROW(validate(p), Error);
  p = RenderParams{};
  p.display.width_cm = 0;
  EXPECT_THROW(validate(p), Error);
  EXPECT_THROW(parse_render_mode("half"), Error);
}

TEST(Render, AutoAmbientConstantIsTheFovealMeanVisibility) {
  const Tracer tracer(box());
  RenderParams p = small_params(RenderMode::foveated);
  p.ambient_constant.reset();
  double last = 0;
  int calls = 0;
  const Frame f = render_frame(tracer, box(), box().cameras.front(), p, [&](double fraction) {
    EXPECT_GE(fraction, last);  // progress never goes back
    last = fraction;
    ++calls;
  });
  EXPECT_EQ(last, 1.0);
  EXPECT_GT(calls, 0);
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < f.visibility.size(); ++i)
    if (f.gbuffer.hit(i) && f.maps.quality[i] == 1.0f) sum += f.visibility[i], ++n;
  ASSERT_GT(n, 0u);
  EXPECT_FLOAT_EQ(f.stats.ambient_constant, static_cast<float>(sum / n));
  EXPECT_LT(f.stats.ambient_constant, 1.0f);  // the box occludes: the fovea is not fully open
}

TEST(Render, ShadowRaysDarkenOnlyWhatTheLightCannotSee) {
  // A light straight above the sphere: with shadows, the plane under it loses the light's term
  Scene scene = make_builtin_scene("sphere-plane");
  scene.lights = {{Light::Type::point, {0, 10, 0}, glm::vec3(0.5f), glm::vec3(0.0f)}};
  const Tracer tracer(scene);
  RenderParams p = small_params(RenderMode::full);
  p.foveation.max_rays = 4;
  const Frame lit = render_frame(tracer, scene, scene.cameras.front(), p);
  p.shadows = true;
  const Frame shadowed = render_frame(tracer, scene, scene.cameras.front(), p);
  EXPECT_GT(shadowed.stats.shadow_rays, 0u);
  size_t under = 0, far = 0;
  for (size_t i = 0; i < lit.visibility.size(); ++i) {
    if (!lit.gbuffer.hit(i)) continue;
    const glm::vec3 x = lit.gbuffer.position[i];
    if (std::abs(x.y) < 1e-3f && glm::length(glm::vec2(x.x, x.z)) < 0.5f) {
      ++under;
      EXPECT_LT(shadowed.color.pixels[3 * i], lit.color.pixels[3 * i] - 0.1f);
    } else if (std::abs(x.y) < 1e-3f && glm::length(glm::vec2(x.x, x.z)) > 3.0f) {
      ++far;
      EXPECT_EQ(shadowed.color.pixels[3 * i], lit.color.pixels[3 * i]);
    }
  }
  EXPECT_GT(under, 10u);
  EXPECT_GT(far, 100u);
  // A light between the plane and the sphere: shadow rays stop at the light, the sphere beyond it casts nothing
  scene.lights = {{Light::Type::point, {0, 0.5f, 0}, glm::vec3(0.5f), glm::vec3(0.0f)}};
  p.shadows = false;
  const Frame low_lit = render_frame(tracer, scene, scene.cameras.front(), p);
  p.shadows = true;
  const Frame low_shadowed = render_frame(tracer, scene, scene.cameras.front(), p);
  for (size_t i = 0; i < low_lit.visibility.size(); ++i)
    if (low_lit.gbuffer.hit(i) && std::abs(low_lit.gbuffer.position[i].y) < 1e-3f && glm::length(low_lit.gbuffer.position[i]) < 0.5f)
      EXPECT_EQ(low_shadowed.color.pixels[3 * i], low_lit.color.pixels[3 * i]);
}

// Issue 36, finding 6: a gaze point must be finite and near the image (one rule, util/gaze_point.h);
// from about 1e155 the foveation model's squares overflowed and the full budget went everywhere.
TEST(Render, AGazeFarFromTheImageIsRefusedWithItsName) {
  RenderParams p = small_params(RenderMode::foveated);
  for (const glm::dvec2 g : {glm::dvec2(1e155, 1e155), glm::dvec2(-1e9, 10), glm::dvec2(10, 1e6), glm::dvec2(NAN, 3)}) {
    p.gaze_px = g;
    try {
      validate(p);
      FAIL() << g.x << "," << g.y;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("gaze_px: ", 0), 0u) << e.what();
    }
  }
  // Off the image but where an eye can look (beside the display): accepted
  for (const glm::dvec2 g : {glm::dvec2(-50, 20), glm::dvec2(200, -100), glm::dvec2(1500, 900)}) {
    p.gaze_px = g;
    EXPECT_NO_THROW(validate(p)) << g.x << "," << g.y;
  }
}
