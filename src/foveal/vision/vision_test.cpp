// The vision simulation's parts: FAST is OpenCV's, saccades are reproducible and glaucoma's are
// shorter, the sharpness field keeps minima and starves lazily exactly as step by step, blinks
// reset it, the blur leaves sharp pixels alone, matches a Gaussian and preserves energy.
#include "foveal/io/image_io.h"
#include "foveal/perception/eye.h"
#include "foveal/scene/scene.h"
#include "foveal/trace/tracer.h"
#include "foveal/vision/blur.h"
#include "foveal/vision/fast.h"
#include "foveal/vision/features.h"
#include "foveal/vision/sharpness.h"
#include "foveal/vision/simulate.h"
#include "foveal/vision/thin_lens.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <random>
#include <set>

using namespace foveal;

namespace {

// A smooth-ish test picture: gradients, a bright square and a dark disc.
Image test_picture(int w, int h) {
  Image img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float v = 0.2f + 0.5f * x / w;
      if (x > w / 4 && x < w / 2 && y > h / 4 && y < h / 2) v = 0.9f;
      if ((x - 3 * w / 4) * (x - 3 * w / 4) + (y - h / 2) * (y - h / 2) < (h / 6) * (h / 6)) v = 0.05f;
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = v * (0.8f + 0.1f * c);
    }
  return img;
}

}  // namespace

TEST(Vision, FastIsOpenCvs) {
  const std::string dir = std::string(FOVEAL_DATA_DIR) + "/images";
  bool any = false;
  for (const char* name : {"building.jpg", "graf1.png", "baboon.jpg"}) {
    const std::string path = dir + "/" + name;
    if (!std::filesystem::exists(path)) continue;
    any = true;
    Image img = load_image(path);  // 8-bit sRGB values in [0, 1]: made linear, as a render is
    for (float& v : img.pixels) v = v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
    // The grey image FAST sees is OpenCV's own greyscale of the file (±1 level from the linear round trip)
    const cv::Mat reference = cv::imread(path, cv::IMREAD_GRAYSCALE);
    const std::vector<uint8_t> grey = grey_8bit(img);
    size_t close = 0;
    for (size_t i = 0; i < grey.size(); ++i) close += std::abs(int(grey[i]) - int(reference.data[i])) <= 1;
    EXPECT_GT(double(close) / grey.size(), 0.99) << name;
    // Every corner is cv::FAST's on that grey image, with its score
    std::vector<cv::KeyPoint> points;
    cv::FAST(cv::Mat(img.height, img.width, CV_8UC1, const_cast<uint8_t*>(grey.data())), points, 20, true,
             cv::FastFeatureDetector::TYPE_9_16);
    const std::vector<Corner> corners = detect_corners(img, 20, true);
    ASSERT_EQ(corners.size(), points.size()) << name;
    ASSERT_GT(corners.size(), 100u) << name;
    std::multiset<std::tuple<float, float, float>> a, b;
    for (const Corner& c : corners) a.insert({c.px.x - 0.5f, c.px.y - 0.5f, c.score});
    for (const cv::KeyPoint& k : points) b.insert({k.pt.x, k.pt.y, k.response});
    EXPECT_EQ(a, b) << name;
    // The per-pixel functions the GPU runs (vision/fast.h) find the same keypoints with the same
    // scores, at several thresholds, with and without non-maximum suppression
    const cv::Mat grey_mat(img.height, img.width, CV_8UC1, const_cast<uint8_t*>(grey.data()));
    for (int threshold : {5, 20, 60})
      for (bool nonmax : {true, false}) {
        std::vector<cv::KeyPoint> expected;
        cv::FAST(grey_mat, expected, threshold, nonmax, cv::FastFeatureDetector::TYPE_9_16);
        const std::vector<Corner> shared = fast_corners(grey, img.width, img.height, threshold, nonmax);
        std::multiset<std::tuple<float, float, float>> got, want;
        // (without suppression OpenCV computes no score and reports 0; ours is kept for the saccades)
        for (const Corner& c : shared) got.insert({c.px.x - 0.5f, c.px.y - 0.5f, nonmax ? c.score : 0.0f});
        for (const cv::KeyPoint& k : expected) want.insert({k.pt.x, k.pt.y, k.response});
        ASSERT_GT(want.size(), 10u) << name << " threshold " << threshold;
        EXPECT_EQ(got, want) << name << " threshold " << threshold << (nonmax ? " nonmax" : "");
      }
  }
  if (!any) GTEST_SKIP() << "skipped: no images under " << dir;
}

TEST(Vision, SharedFastMatchesOpenCvOnRenderedAndSyntheticImages) {
  // Without the data: a rendered picture and noise with flat patches (ties in the non-maximum
  // suppression, corners at the 3-pixel border, saturated values)
  std::vector<std::pair<std::string, Image>> images;
  images.emplace_back("test picture", test_picture(160, 120));
  Image noise(97, 64, 3);
  std::mt19937 rng(7);
  for (int y = 0; y < noise.height; ++y)
    for (int x = 0; x < noise.width; ++x) {
      const float v = (x / 8 + y / 8) % 3 == 0 ? 0.5f : float(rng() % 1000) / 999.0f;
      for (int c = 0; c < 3; ++c) noise.at(x, y, c) = c == 0 ? v : v * v;
    }
  images.emplace_back("noise", noise);
  for (const auto& [name, img] : images) {
    const std::vector<uint8_t> grey = grey_8bit(img);
    const cv::Mat grey_mat(img.height, img.width, CV_8UC1, const_cast<uint8_t*>(grey.data()));
    for (int threshold : {1, 10, 30, 255})
      for (bool nonmax : {true, false}) {
        std::vector<cv::KeyPoint> expected;
        cv::FAST(grey_mat, expected, threshold, nonmax, cv::FastFeatureDetector::TYPE_9_16);
        std::multiset<std::tuple<float, float, float>> got, want;
        for (const Corner& c : fast_corners(grey, img.width, img.height, threshold, nonmax))
          got.insert({c.px.x - 0.5f, c.px.y - 0.5f, nonmax ? c.score : 0.0f});
        for (const cv::KeyPoint& k : expected) want.insert({k.pt.x, k.pt.y, k.response});
        if (threshold < 255) EXPECT_GT(want.size(), 0u) << name << " threshold " << threshold;
        EXPECT_EQ(got, want) << name << " threshold " << threshold << (nonmax ? " nonmax" : "");
      }
  }
  // The GPU's grey conversion is cv::cvtColor's for every one of the 2^24 sRGB triples
  cv::Mat rgb(4096, 4096, CV_8UC3);
  for (uint32_t i = 0; i < (1u << 24); ++i) {
    uint8_t* p = rgb.data + size_t(i) * 3;
    p[0] = uint8_t(i >> 16);
    p[1] = uint8_t(i >> 8);
    p[2] = uint8_t(i);
  }
  cv::Mat grey;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  size_t differ = 0;
  for (uint32_t i = 0; i < (1u << 24); ++i) differ += fast::grey_of(i >> 16, (i >> 8) & 255, i & 255) != grey.data[i];
  EXPECT_EQ(differ, 0u);
  // and its linear → sRGB byte table is the CPU's
  const std::vector<uint8_t>& table = srgb8_table();
  ASSERT_EQ(table.size(), 4097u);
  EXPECT_EQ(table[0], 0);
  EXPECT_EQ(table[4096], 255);
  EXPECT_EQ(table[737], 118);  // linear 0.18 (grey card) → sRGB 0.461
}

TEST(Vision, SaccadesAreReproducibleAndGlaucomaShortensThem) {
  // Corners on a grid over a 640×400 image
  std::vector<Corner> corners;
  for (int y = 10; y < 400; y += 23)
    for (int x = 10; x < 640; x += 29) corners.push_back({{float(x), float(y)}, float(20 + (x * 7 + y * 13) % 50)});
  auto path = [&](const EyeParams& eye, uint64_t seed, std::vector<glm::vec2>* out) {
    SaccadeModel m(saccade_params_for(eye), 15.0, seed);
    double length = 0;
    glm::vec2 last{0};
    for (int k = 0; k < 60; ++k) {
      const glm::vec2 p = m.next(corners, {640, 400});
      if (k > 0) length += glm::length(p - last);
      last = p;
      if (out) out->push_back(p);
    }
    return length;
  };
  std::vector<glm::vec2> a, b, c;
  path(EyeParams{}, 7, &a);
  path(EyeParams{}, 7, &b);
  path(EyeParams{}, 8, &c);
  EXPECT_EQ(a, b);  // same seed, same fixations
  EXPECT_NE(a, c);
  // The first fixation is drawn around the centre
  EXPECT_LT(glm::length(a[0] - glm::vec2(320, 200)), 250.0f);
  double healthy = 0, glaucoma = 0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    healthy += path(parse_eye_preset("healthy"), seed, nullptr);
    glaucoma += path(parse_eye_preset("glaucoma:0.8"), seed, nullptr);
  }
  EXPECT_LT(glaucoma, 0.6 * healthy);
}

TEST(Vision, SharpnessFieldKeepsMinimaStarvesLazilyAndBlinks) {
  Bounds bounds;
  bounds.lo = glm::vec3(0);
  bounds.hi = glm::vec3(1);
  SharpnessField field(bounds, 0.25f, 0.015);
  const int64_t c = field.cell({0.6f, 0.6f, 0.6f});
  ASSERT_GE(c, 0);
  EXPECT_EQ(field.cell({5, 5, 5}), -1);
  EXPECT_EQ(field.cell(glm::vec3(NAN)), -1);
  EXPECT_TRUE(std::isinf(field.effective(c, 1)));
  EXPECT_TRUE(field.update(c, 2.0f, 1));
  EXPECT_FALSE(field.update(c, 3.0f, 1));  // larger: kept the smaller
  EXPECT_TRUE(field.update(c, 1.0f, 1));
  EXPECT_FLOAT_EQ(field.effective(c, 1), 1.0f);
  // Lazy starvation equals multiplying by (1 + s) every step
  double naive = 1.0;
  for (uint32_t t = 2; t <= 200; ++t) {
    naive *= 1.015;
    EXPECT_NEAR(field.effective(c, t), naive, 1e-4 * naive) << "step " << t;
  }
  // A starved cell accepts a CoC that is smaller than the starved value, not the stored one
  EXPECT_TRUE(field.update(c, 1.5f, 100));
  EXPECT_FLOAT_EQ(field.effective(c, 100), 1.5f);
  // A blink forgets everything at once
  field.blink();
  EXPECT_TRUE(std::isinf(field.effective(c, 100)));
  EXPECT_TRUE(field.update(c, 4.0f, 101));
}

// The GPU's update (every pixel at once: atomic minima per cell, then the cell's first pixel
// writes) run here with real threads and in shuffled order, against the CPU's pixel-order loop:
// the same field after every step, through skipped steps and blinks, with ties, zeros of both
// signs, infinities and NaNs among the CoCs.
TEST(Vision, ConcurrentFieldUpdateIsThePixelOrderUpdate) {
  Bounds bounds;
  bounds.lo = glm::vec3(0);
  bounds.hi = glm::vec3(1);
  SharpnessField ordered(bounds, 0.125f, 0.015), concurrent(bounds, 0.125f, 0.015);
  const size_t cells = concurrent.cells(), n = 20000;
  std::vector<unsigned long long> cell_min(cells, ~0ULL), cell_owner(cells, ~0ULL);
  ConcurrentFieldUpdate update{cell_min.data(), cell_owner.data(), 0};
  std::mt19937 rng(7);
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  size_t applied_total = 0;
  for (uint32_t step = 1; step <= 40; ++step) {
    if (step % 9 == 0) {
      ordered.blink();
      concurrent.blink();
    }
    // Few cells for many pixels (contention), a tenth background; CoCs on a coarse grid (ties)
    std::vector<int64_t> cell(n);
    std::vector<float> coc(n);
    for (size_t i = 0; i < n; ++i) {
      const uint32_t r = rng();
      cell[i] = r % 10 == 0 ? -1 : int64_t((r >> 4) % std::min<size_t>(cells, 300));
      const uint32_t v = (r >> 12) % 64;
      coc[i] = v == 0 ? 0.0f : v == 1 ? -0.0f : v == 2 ? INFINITY : v == 3 ? NAN : 0.05f * float(v % 40) + 0.01f * step;
    }
    if (step % 7 == 3) continue;  // glaucoma's skipped step: neither field is updated, no serial used
    for (size_t i = 0; i < n; ++i) ordered.update(cell[i], coc[i], step);
    ++update.serial;
    std::shuffle(order.begin(), order.end(), rng);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) update.offer(cell[order[k]], coc[order[k]], order[k]);
    });
    std::atomic<size_t> applied{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) applied += update.apply(concurrent.view(), cell[order[k]], order[k], step) ? 1 : 0;
    });
    applied_total += applied;
    for (size_t c = 0; c < cells; ++c) {
      const float a = ordered.effective(int64_t(c), step), b = concurrent.effective(int64_t(c), step);
      ASSERT_TRUE(a == b) << "cell " << c << " step " << step << ": " << a << " vs " << b;
      ASSERT_EQ(ordered.effective(int64_t(c), step + 5), concurrent.effective(int64_t(c), step + 5)) << "cell " << c;
    }
  }
  EXPECT_GT(applied_total, 300u);  // cells were written, again and again
}

TEST(Vision, BlurLeavesSharpPixelsMatchesAGaussianAndPreservesEnergy) {
  const Image img = test_picture(160, 120);
  const size_t n = size_t(img.width) * img.height;
  // Zero CoC: unchanged, bit for bit
  const Image same = variable_blur(img, std::vector<float>(n, 0.0f));
  EXPECT_EQ(same.pixels, img.pixels);
  // Constant CoC d: a Gaussian of σ = d/6 (OpenCV), within 0.02 everywhere away from the border
  const float d = 12;
  const Image blurred = variable_blur(img, std::vector<float>(n, d));
  cv::Mat src(img.height, img.width, CV_32FC3, const_cast<float*>(img.pixels.data())), ref;
  cv::GaussianBlur(src, ref, cv::Size(0, 0), d / 6.0, d / 6.0, cv::BORDER_REPLICATE);
  double max_error = 0, mean_error = 0;
  size_t count = 0;
  for (int y = 8; y < img.height - 8; ++y)
    for (int x = 8; x < img.width - 8; ++x)
      for (int c = 0; c < 3; ++c) {
        const double e = std::abs(blurred.at(x, y, c) - ref.at<cv::Vec3f>(y, x)[c]);
        max_error = std::max(max_error, e);
        mean_error += e;
        ++count;
      }
  EXPECT_LT(max_error, 0.02);
  EXPECT_LT(mean_error / count, 0.002);
  // Energy: a constant image stays constant; the mean is kept where the border plays no part
  Image flat(64, 64, 3, 0.37f);
  for (float v : variable_blur(flat, std::vector<float>(64 * 64, 9.0f)).pixels) EXPECT_NEAR(v, 0.37f, 1e-5f);
  Image spot(64, 64, 1, 0.0f);
  for (int y = 28; y < 36; ++y)
    for (int x = 28; x < 36; ++x) spot.at(x, y) = 1.0f;
  double before = 0, after = 0;
  for (float v : spot.pixels) before += v;
  for (float v : variable_blur(spot, std::vector<float>(64 * 64, 10.0f)).pixels) after += v;
  EXPECT_NEAR(after, before, 0.02 * before);
}

TEST(Vision, BlurKernelDiffersPerPixelAndIsNotSeparable) {
  // The response to a single bright pixel, gathered by its neighbours: the kernel of each pixel
  const int size = 41;
  Image impulse(size, size, 1, 0.0f);
  impulse.at(20, 20) = 1.0f;
  std::vector<float> coc(size * size, 14.0f);
  const Image k = variable_blur(impulse, coc);
  // Not separable: the kernel differs from the outer product of its row and column sums
  double total = 0, error = 0, mass = 0;
  std::vector<double> rows(size, 0), cols(size, 0);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      rows[y] += k.at(x, y);
      cols[x] += k.at(x, y);
      total += k.at(x, y);
    }
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      error += std::abs(k.at(x, y) - rows[y] * cols[x] / total);
      mass += k.at(x, y);
    }
  EXPECT_GT(error / mass, 0.05);
  // Per pixel: next to a pixel with a large CoC, one with a small CoC gathers from a smaller area
  coc.assign(size * size, 14.0f);
  coc[20 * size + 24] = 2.0f;  // 4 px right of the impulse
  const Image mixed = variable_blur(impulse, coc);
  EXPECT_GT(mixed.at(26, 20), 0.0f);  // CoC 14, 6 px away: reaches the impulse
  EXPECT_EQ(mixed.at(24, 20), 0.0f);  // CoC 2, 4 px away: does not
  // Scatter-aware: a sharp impulse does not spread into blurred neighbours; without it, it does
  coc.assign(size * size, 14.0f);
  coc[20 * size + 20] = 0.0f;
  BlurParams plain;
  plain.scatter_aware = false;
  const float spread = variable_blur(impulse, coc, plain).at(23, 20), kept = variable_blur(impulse, coc).at(23, 20);
  EXPECT_GT(spread, 0.0f);
  EXPECT_LT(kept, 0.25f * spread);  // only what bilinear reads next to the impulse still carry
}

TEST(Vision, SimulationSharpensOverStepsAndForgetsAtABlink) {
  const Scene scene = load_scene("builtin:box");
  const Tracer tracer(scene);
  SimulateParams p;
  p.width = 160;
  p.height = 100;
  p.blink_every = 12;
  p.seed = 3;
  VisionSimulation sim(tracer, scene, p);
  const Camera camera = scene.cameras.front();
  std::vector<StepStats> steps;
  for (int k = 0; k < 14; ++k) steps.push_back(sim.step(camera));
  EXPECT_TRUE(steps[0].camera_moved);
  EXPECT_FALSE(steps[1].camera_moved);
  EXPECT_GT(steps[0].corners, 10u);
  EXPECT_GT(steps[10].sharp_fraction, steps[0].sharp_fraction);  // sharp regions grow
  EXPECT_TRUE(steps[12].blink);
  EXPECT_LT(steps[12].sharp_fraction, steps[11].sharp_fraction);  // and are forgotten at a blink
  // A moving camera: corners recomputed at every step that moved
  VisionSimulation moving(tracer, scene, p);
  Camera c = camera;
  EXPECT_TRUE(moving.step(c).camera_moved);
  EXPECT_FALSE(moving.step(c).camera_moved);
  c.eye += glm::vec3(0.05f, 0, 0);
  EXPECT_TRUE(moving.step(c).camera_moved);
  // Reproducible: the same seed gives the same fixations and the same image
  VisionSimulation again(tracer, scene, p);
  for (int k = 0; k < 14; ++k) EXPECT_EQ(again.step(camera).focus_px, steps[k].focus_px);
  EXPECT_EQ(again.perceived().pixels, sim.perceived().pixels);
  // Recomputing the corners every step (the benchmark's timing) changes no fixation: the eye
  // remembers its recent fixations as long as the camera stays
  SimulateParams every = p;
  every.features_every_step = true;
  VisionSimulation timed(tracer, scene, every);
  for (int k = 0; k < 14; ++k) EXPECT_EQ(timed.step(camera).focus_px, steps[k].focus_px) << "step " << k + 1;
}

TEST(Vision, BlurApproximatesTheThinLensReference) {
  // A large pupil (150 mm) makes the box's depth range blur by several pixels at this size
  const Scene scene = load_scene("builtin:box");
  const Tracer tracer(scene);
  const Camera camera = scene.cameras.front();
  ThinLensParams p;
  p.width = 256;
  p.height = 160;
  p.samples = 64;
  p.pupil_diameter_mm = 150;
  ThinLensParams pinhole = p;
  pinhole.samples = 1;
  pinhole.pupil_diameter_mm = 1e-6;
  const Image sharp = thin_lens_reference(tracer, scene, camera, pinhole);
  auto mean_error = [](const Image& a, const Image& b) {  // on the sRGB values a viewer sees
    double e = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) e += std::abs(linear_to_srgb(a.pixels[i]) - linear_to_srgb(b.pixels[i]));
    return e / a.pixels.size();
  };
  EXPECT_LT(mean_error(sharp, thin_lens_approximation(tracer, scene, camera, pinhole)), 1e-4);  // no CoC: the pinhole image
  for (double focus_m : {4.3, 8.2}) {                                                           // near wall, far wall
    p.focus_vergence = 1.0 / focus_m;
    const Image reference = thin_lens_reference(tracer, scene, camera, p);
    const double blurred = mean_error(thin_lens_approximation(tracer, scene, camera, p), reference);
    const double unblurred = mean_error(sharp, reference);
    EXPECT_LT(blurred, 0.8 * unblurred) << "focus " << focus_m << " m";
  }
  EXPECT_NEAR(camera_pixels_per_degree(camera, 100), 50.0 / std::tan(glm::radians(0.5 * camera.fov_deg)) * M_PI / 180, 1e-9);
}

TEST(Vision, AstigmatismBlursAlongItsAxis) {
  // The eye: the circle of least confusion at the fixation, a line blur elsewhere
  const EyeParams eye = parse_eye_preset("astigmatism:2@0");
  const double v = accommodate(eye, 0.5);  // wants 2 D, aims at 2 − C/2 = 1 D
  EXPECT_NEAR(v, 1.0, 1e-12);
  const glm::dvec2 at_fixation = coc_axes_rad(eye, 0.5, v);
  EXPECT_NEAR(at_fixation.x, at_fixation.y, 1e-12);  // round
  const glm::dvec2 at_1m = coc_axes_rad(eye, 1.0, v);
  EXPECT_NEAR(at_1m.x, 0.0, 1e-12);         // sharp along the axis …
  EXPECT_NEAR(at_1m.y, 3.5e-3 * 2, 1e-12);  // … blurred across it
  // The blur: an impulse spreads along the ellipse's long axis only
  const int size = 41;
  Image impulse(size, size, 1, 0.0f);
  impulse.at(20, 20) = 1.0f;
  const std::vector<float> coc(size * size, 14.0f);
  CocShape shape;
  shape.scale.assign(size * size, glm::vec2(1.0f, 0.15f));  // long along the axis
  for (float axis : {0.0f, 90.0f}) {
    shape.axis_deg = axis;
    const Image k = variable_blur(impulse, coc, {}, &shape);
    const float horizontal = k.at(25, 20), vertical = k.at(20, 25);
    if (axis == 0.0f) {
      EXPECT_GT(horizontal, 0.0f);
      EXPECT_EQ(vertical, 0.0f);
    } else {
      EXPECT_EQ(horizontal, 0.0f);
      EXPECT_GT(vertical, 0.0f);
    }
  }
}

// Where an eye at the camera sees each pixel (CameraRetinotopy, what the impairments are centred
// by): with the fixation at the image centre a pixel on the centre row lies at the angle of its
// ray, atan(s·tan(fov/2)·aspect) to the right; off-centre, every pixel's eccentricity is the
// angle between its ray and the fixation's (double precision); pixels right of and above the
// fixation lie right and up; and the grid of every 4th pixel, expanded bilinearly, is within
// 1.5e-3° of the rule at every pixel of 1280×720 with 60° of view.
TEST(Vision, CameraRetinotopyIsTheAngleFromTheFixation) {
  Camera camera;
  camera.eye = {0.3f, 1.2f, 4.0f};
  camera.look = {-0.2f, 0.4f, 0.0f};
  camera.fov_deg = 60.0f;
  const int w = 1280, h = 720;
  const double tan_half = std::tan(glm::radians(60.0) / 2), aspect = double(w) / h;

  const CameraRetinotopy centred(camera, w, h, {w / 2.0f, h / 2.0f});
  for (int x : {0, 17, 300, 639, 640, 901, 1279}) {
    const double s = 2.0 * (x + 0.5) / w - 1.0;
    const glm::vec2 p = centred(x + 0.5, h / 2.0);
    EXPECT_NEAR(p.x, glm::degrees(std::atan(s * tan_half * aspect)), 1e-3) << "x " << x;
    EXPECT_NEAR(p.y, 0.0, 1e-3) << "x " << x;
  }
  for (int y : {0, 100, 359, 500, 719}) {
    const double s = 1.0 - 2.0 * (y + 0.5) / h;
    const glm::vec2 p = centred(w / 2.0, y + 0.5);
    EXPECT_NEAR(p.y, glm::degrees(std::atan(s * tan_half)), 1e-3) << "y " << y;
    EXPECT_NEAR(p.x, 0.0, 1e-3) << "y " << y;
  }

  const glm::vec2 fixation{310.0f, 505.0f};
  const CameraRetinotopy where(camera, w, h, fixation);
  const CameraRays rays(camera, w, h);
  const glm::dvec3 g = glm::normalize(glm::dvec3(rays(fixation.x, fixation.y).dir));
  double worst_angle = 0;
  for (int y = 0; y < h; y += 37)
    for (int x = 0; x < w; x += 41) {
      const glm::dvec3 d = glm::normalize(glm::dvec3(rays(x + 0.5, y + 0.5).dir));
      const double exact = glm::degrees(std::atan2(glm::length(glm::cross(g, d)), glm::dot(g, d)));
      worst_angle = std::max(worst_angle, std::abs(double(glm::length(where(x + 0.5, y + 0.5))) - exact));
    }
  EXPECT_LT(worst_angle, 1e-3);
  EXPECT_NEAR(glm::length(where(fixation.x, fixation.y)), 0.0, 1e-3);
  // (off the image's centre, a row or column of pixels is no great circle through the fixation:
  // the other coordinate drifts a little)
  const glm::vec2 right = where(fixation.x + 200, fixation.y), up = where(fixation.x, fixation.y - 200);
  EXPECT_GT(right.x, 10.0);
  EXPECT_LT(std::abs(right.y), 0.2 * right.x);
  EXPECT_GT(up.y, 10.0);
  EXPECT_LT(std::abs(up.x), 0.2 * up.y);

  // (the grid's error is largest far from the fixation: 1.1e-3–1.2e-3° for these four)
  for (glm::vec2 f : {glm::vec2{640, 360}, glm::vec2{0, 0}, glm::vec2{1279, 719}, fixation}) {
    const CameraRetinotopy at(camera, w, h, f);
    const Retinotopy all = expand(at.grid());
    ASSERT_EQ(all.field_deg.size(), size_t(w) * h);
    std::vector<double> worst_row(h, 0.0);
    tbb::parallel_for(0, h, [&](int y) {
      for (int x = 0; x < w; ++x)
        worst_row[y] = std::max(worst_row[y], double(glm::length(all.field_deg[size_t(y) * w + x] - at(x + 0.5, y + 0.5))));
    });
    EXPECT_LT(*std::max_element(worst_row.begin(), worst_row.end()), 1.5e-3) << "fixation " << f.x << "," << f.y;
  }
  const RetinotopyGrid grid = where.grid();
  ASSERT_EQ(grid.columns, (w + 3) / 4 + 1);
  ASSERT_EQ(grid.rows, (h + 3) / 4 + 1);
  EXPECT_EQ(grid.ppd, camera_pixels_per_degree(camera, h));
  EXPECT_EQ(grid.field_deg[size_t(7) * grid.columns + 9], where(9 * 4 + 0.5, 7 * 4 + 0.5));
  EXPECT_TRUE(where.sizes().field_deg.empty());
  EXPECT_EQ(where.sizes().columns, grid.columns);
}
