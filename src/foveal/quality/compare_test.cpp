// Image-quality metrics against known answers: identical images, Wang et al.'s SSIM formula
// evaluated directly on the natural images, bands from the renderer's eccentricity, the noise
// verdict on images of known noise, and the paper's setting.
#include "foveal/io/image_io.h"
#include "foveal/quality/compare.h"
#include "foveal/render/render.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <random>

namespace foveal {
namespace {

Image noisy(const Image& base, float sigma, uint32_t seed) {
  Image out = base;
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, sigma);
  for (float& v : out.pixels) v += n(rng);
  return out;
}

Image gradient(int w, int h) {
  Image img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 0.2f + 0.6f * (x + c * y) / static_cast<float>(w + 2 * h);
  return img;
}

TEST(Compare, IdenticalImagesArePerfect) {
  const Image a = gradient(120, 80);
  const Comparison c = compare_images(a, a, nullptr, Display{}, {60, 40}, FoveationParams{});
  EXPECT_EQ(c.whole.rmse, 0.0);
  EXPECT_TRUE(std::isinf(c.whole.psnr));
  EXPECT_NEAR(c.whole.ssim, 1.0, 1e-12);
  for (const BandResult& r : c.bands)
    if (r.error.pixels) EXPECT_TRUE(std::isinf(r.error.psnr)) << r.band.name;
  const Comparison d = compare_images(noisy(a, 0.01f, 1), a, nullptr, Display{}, {60, 40}, FoveationParams{});
  EXPECT_NEAR(d.whole.rmse, 0.01, 0.0005);
  EXPECT_NEAR(d.whole.psnr, 40.0, 0.5);
  EXPECT_LT(d.whole.ssim, 1.0);
}

TEST(Compare, BadInputIsRefused) {
  const Image a = gradient(20, 10), b = gradient(10, 20);
  EXPECT_THROW(compare_images(a, b, nullptr, Display{}, {0, 0}, FoveationParams{}), Error);
  Image grey(20, 10, 1);
  EXPECT_THROW(compare_images(a, grey, nullptr, Display{}, {0, 0}, FoveationParams{}), Error);
}

// SSIM at one pixel straight from Wang et al. (2004): Gaussian-weighted means, variances and
// covariance over the 11×11 window (σ = 1.5, weights summing to 1), borders reflected as OpenCV's
// default (…cb|abcd|cb…), C1 = (0.01)², C2 = (0.03)².
// Each channel of an image as a float64 matrix.
std::vector<cv::Mat> channels_f64(const Image& img) {
  std::vector<cv::Mat> out(img.channels);
  for (int c = 0; c < img.channels; ++c) {
    out[c].create(img.height, img.width, CV_64F);
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) out[c].at<double>(y, x) = img.at(x, y, c);
  }
  return out;
}

double ssim_at(const cv::Mat& x, const cv::Mat& y, int px, int py) {
  const cv::Mat g = cv::getGaussianKernel(11, 1.5, CV_64F);
  auto reflect = [](int i, int n) { return i < 0 ? -i : i >= n ? 2 * n - 2 - i : i; };
  double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
  for (int dy = -5; dy <= 5; ++dy)
    for (int dx = -5; dx <= 5; ++dx) {
      const double w = g.at<double>(dy + 5) * g.at<double>(dx + 5);
      const int yy = reflect(py + dy, x.rows), xx = reflect(px + dx, x.cols);
      const double a = x.at<double>(yy, xx), b = y.at<double>(yy, xx);
      mx += w * a;
      my += w * b;
      sxx += w * a * a;
      syy += w * b * b;
      sxy += w * a * b;
    }
  sxx -= mx * mx;
  syy -= my * my;
  sxy -= mx * my;
  const double c1 = 1e-4, c2 = 9e-4;
  return (2 * mx * my + c1) * (2 * sxy + c2) / ((mx * mx + my * my + c1) * (sxx + syy + c2));
}

TEST(Compare, SsimIsWangsFormulaOnNaturalImages) {
  const std::filesystem::path dir = FOVEAL_DATA_DIR "/images";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "skipped: " << dir << " absent";
  int checked = 0;
  for (const char* name : {"baboon.jpg", "building.jpg", "graf1.png"}) {
    const Image img = load_image((dir / name).string());
    // A distorted copy: a blur, a contrast change and noise (as a foveated render's errors are)
    Image other = img;
    for (int c = 0; c < img.channels; ++c) {
      cv::Mat ch(img.height, img.width, CV_32F), out;
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) ch.at<float>(y, x) = img.at(x, y, c);
      cv::GaussianBlur(ch, out, {0, 0}, 1.2 + c * 0.5);
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) other.at(x, y, c) = 0.9f * out.at<float>(y, x) + 0.03f;
    }
    other = noisy(other, 0.02f, 7);
    const std::vector<float> map = ssim_map(other, img);
    const std::vector<cv::Mat> a = channels_f64(other), b = channels_f64(img);
    std::mt19937 rng(3);
    for (int k = 0; k < 60; ++k) {
      // random pixels, the first ones on the borders (where the window is reflected)
      const int x = k == 0 ? 0 : k == 1 ? img.width - 1 : static_cast<int>(rng() % img.width);
      const int y = k == 0 ? 0 : k == 1 ? img.height - 1 : static_cast<int>(rng() % img.height);
      double expected = 0;
      for (int c = 0; c < img.channels; ++c) expected += ssim_at(a[c], b[c], x, y);
      expected /= img.channels;
      ASSERT_NEAR(map[static_cast<size_t>(y) * img.width + x], expected, 1e-5) << name << " at " << x << "," << y;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 180);
}

TEST(Compare, BandsFollowTheRenderersEccentricity) {
  const int w = 300, h = 180;
  const Image a = gradient(w, h);
  const glm::dvec2 gaze(80, 70);
  const FoveationParams params;
  const Comparison c = compare_images(noisy(a, 0.05f, 2), a, nullptr, Display{}, gaze, params);
  RenderParams rp;
  rp.width = w;
  rp.height = h;
  rp.display = Display{};
  rp.foveation = params;
  const FoveationMaps maps = foveation_maps(rp, gaze);  // what the renderer computes per pixel
  const FoveationModel model(Display{}, w, h, gaze, params);
  std::vector<size_t> expected(c.bands.size(), 0);
  size_t q1 = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double e = model.evaluate(x, y).angle_deg;
      for (size_t k = 0; k < c.bands.size(); ++k)
        if (!c.bands[k].band.foveal_region && e >= c.bands[k].band.lo_deg && e < c.bands[k].band.hi_deg) ++expected[k];
      q1 += maps.quality[static_cast<size_t>(y) * w + x] >= 1.0f;
    }
  size_t total = 0;
  for (size_t k = 0; k < c.bands.size(); ++k) {
    if (c.bands[k].band.foveal_region) {
      EXPECT_EQ(c.bands[k].error.pixels, q1);
      EXPECT_GT(q1, 100u);
    } else {
      EXPECT_EQ(c.bands[k].error.pixels, expected[k]) << c.bands[k].band.name;
      total += c.bands[k].error.pixels;
    }
  }
  EXPECT_EQ(total, static_cast<size_t>(w) * h);  // the ranges cover the image once
}

TEST(Compare, NoiseVerdictOnImagesOfKnownNoise) {
  const Image base = gradient(200, 120);
  const Image ref = noisy(base, 0.02f, 1), ref2 = noisy(base, 0.02f, 2);
  const Comparison same = compare_images(noisy(base, 0.02f, 3), ref, &ref2, Display{}, {100, 60}, FoveationParams{});
  const Comparison worse = compare_images(noisy(base, 0.06f, 3), ref, &ref2, Display{}, {100, 60}, FoveationParams{});
  for (size_t k = 0; k < same.bands.size(); ++k) {
    if (same.bands[k].error.pixels < 500) continue;
    EXPECT_NEAR(same.bands[k].noise_ratio, 1.0, 0.1) << same.bands[k].band.name;
    EXPECT_TRUE(same.bands[k].within_noise) << same.bands[k].band.name;
    // √(0.06² + 0.02²) / √(0.02² + 0.02²) = 2.24
    EXPECT_NEAR(worse.bands[k].noise_ratio, 2.24, 0.15) << worse.bands[k].band.name;
    EXPECT_FALSE(worse.bands[k].within_noise) << worse.bands[k].band.name;
  }
}

TEST(Compare, PaperSettingIsWithinTheReferencesNoiseAtTheFovea) {
  const std::string dragon = FOVEAL_DATA_DIR "/scenes/dragon/dragon.obj";
  if (!std::filesystem::exists(dragon)) GTEST_SKIP() << "skipped: " << dragon << " absent";
  const Scene scene = load_scene(FOVEAL_SOURCE_DIR "/scenes/dragon-box.json");
  const Tracer tracer(scene);
  const Camera camera = find_camera(scene, "camera1");
  RenderParams p;  // 840×525, n_max 400, γ 2, the paper's display
  p.gaze_px = glm::dvec2(418, 292);
  p.seed = 1;
  const Image foveated = render_frame(tracer, scene, camera, p).color;
  p.mode = RenderMode::full;
  p.seed = 2;
  const Image reference = render_frame(tracer, scene, camera, p).color;
  p.seed = 3;
  const Image reference2 = render_frame(tracer, scene, camera, p).color;
  const Comparison c = compare_images(foveated, reference, &reference2, p.display, *p.gaze_px, p.foveation);
  const BandResult& fovea = c.bands.back();
  ASSERT_TRUE(fovea.band.foveal_region);
  EXPECT_GT(fovea.error.pixels, 10000u);
  EXPECT_TRUE(fovea.within_noise) << "ratio " << fovea.noise_ratio << " ± " << fovea.ratio_se;
  EXPECT_FALSE(c.bands[3].within_noise);  // 10–20°: a quarter of the rays or fewer there
}

}  // namespace
}  // namespace foveal

namespace foveal {

// --ssim-border valid is the reference convention (Wang et al.'s code, scikit-image): the mean of
// the SSIM map over the windows lying wholly inside the image, computed here the direct way.
TEST(Compare, SsimValidBorderIsTheReferenceConvention) {
  std::vector<std::pair<std::string, Image>> images{{"synthetic", noisy(gradient(60, 44), 0.05f, 11)}};
  const std::filesystem::path baboon = FOVEAL_DATA_DIR "/images/baboon.jpg";
  if (std::filesystem::exists(baboon)) images.emplace_back("baboon", load_image(baboon.string()));
  const Display display{47.5, 30, 60, 1680, 1050};
  for (const auto& [name, img] : images) {
    const Image other = noisy(img, 0.03f, 5);
    const std::vector<cv::Mat> a = channels_f64(other), b = channels_f64(img);
    double sum = 0;
    size_t count = 0;
    for (int y = 5; y < img.height - 5; ++y)
      for (int x = 5; x < img.width - 5; ++x, ++count)
        for (int c = 0; c < img.channels; ++c) sum += ssim_at(a[c], b[c], x, y) / img.channels;
    const double reference = sum / count;
    const Comparison valid =
        compare_images(other, img, nullptr, display, {img.width / 2.0, img.height / 2.0}, {}, default_bands(), SsimBorder::valid);
    EXPECT_EQ(valid.whole.ssim_pixels, count) << name;
    EXPECT_NEAR(valid.whole.ssim, reference, 1e-6) << name;
    EXPECT_TRUE(std::isnan(valid.ssim_map[0])) << name;
    // The default mirrors the image at the edges and counts every pixel: a different number
    const Comparison reflect = compare_images(other, img, nullptr, display, {img.width / 2.0, img.height / 2.0}, {});
    EXPECT_EQ(reflect.whole.ssim_pixels, static_cast<size_t>(img.width) * img.height);
    EXPECT_GT(std::abs(reflect.whole.ssim - reference), 1e-5) << name;
    std::printf("%s: SSIM valid %.6f, reflect %.6f\n", name.c_str(), valid.whole.ssim, reflect.whole.ssim);
  }
  EXPECT_THROW(parse_ssim_border("mirror"), Error);
}

}  // namespace foveal
