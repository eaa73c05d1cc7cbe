// foveal/vision/features.cpp — FAST through OpenCV, saccades from one seeded generator.
#include "foveal/vision/features.h"

#include "foveal/io/image_io.h"
#include "foveal/util/error.h"
#include "foveal/vision/fast.h"

#include <tbb/parallel_for.h>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace foveal {

const std::vector<uint8_t>& srgb8_table() {
  static const std::vector<uint8_t> table = [] {
    std::vector<uint8_t> t(4097);
    for (int k = 0; k <= 4096; ++k) t[k] = static_cast<uint8_t>(std::lround(255.0f * linear_to_srgb(k / 4096.0f)));
    return t;
  }();
  return table;
}

std::vector<uint8_t> grey_8bit(const Image& img) {
  if (img.channels < 3) fail("features: need an RGB image, got {} channels", img.channels);
  // linear → 8-bit sRGB through a table (4096 steps of the clamped linear value)
  const std::vector<uint8_t>& table = srgb8_table();
  cv::Mat rgb(img.height, img.width, CV_8UC3);
  uint8_t* out = rgb.ptr<uint8_t>();
  const size_t n = size_t(img.width) * img.height;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const float v = img.pixels[i * img.channels + c];
      out[i * 3 + c] = table[fast::srgb8_index(v)];
    }
  cv::Mat grey;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  return std::vector<uint8_t>(grey.datastart, grey.dataend);
}

std::vector<Corner> detect_corners(const Image& img, int threshold, bool nonmax) {
  std::vector<uint8_t> grey = grey_8bit(img);
  const cv::Mat mat(img.height, img.width, CV_8UC1, grey.data());
  std::vector<cv::KeyPoint> points;
  cv::FAST(mat, points, threshold, nonmax, cv::FastFeatureDetector::TYPE_9_16);
  std::vector<Corner> corners;
  corners.reserve(points.size());
  for (const cv::KeyPoint& k : points) corners.push_back({{k.pt.x + 0.5f, k.pt.y + 0.5f}, k.response});
  // A fixed order (OpenCV's is by row, but do not depend on it): by row, then column
  std::sort(corners.begin(), corners.end(),
            [](const Corner& a, const Corner& b) { return a.px.y != b.px.y ? a.px.y < b.px.y : a.px.x < b.px.x; });
  return corners;
}

std::vector<Corner> fast_corners(const std::vector<uint8_t>& grey, int w, int h, int threshold, bool nonmax) {
  if (grey.size() != size_t(w) * h) fail("features: {} grey values for a {}x{} image", grey.size(), w, h);
  std::vector<uint8_t> scores(grey.size());
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) scores[size_t(y) * w + x] = static_cast<uint8_t>(fast::score(grey.data(), w, h, x, y, threshold));
  });
  std::vector<Corner> corners;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint8_t s = scores[size_t(y) * w + x];
      if (s > 0 && (!nonmax || fast::is_local_maximum(scores.data(), w, h, x, y))) corners.push_back({{x + 0.5f, y + 0.5f}, float(s)});
    }
  return corners;
}

SaccadeModel::SaccadeModel(const SaccadeParams& params, double ppd, uint64_t seed) : params_(params), ppd_(ppd), rng_(seed) {
  if (!(ppd > 0)) fail("saccades: pixels per degree must be positive");
}

double SaccadeModel::uniform() {
  // 53 random bits → [0, 1); the same on every platform (std::uniform_real_distribution is not)
  return static_cast<double>(rng_() >> 11) * 0x1.0p-53;
}

void SaccadeModel::set_pixels_per_degree(double ppd) {
  if (!(ppd > 0)) fail("saccades: pixels per degree must be positive");
  ppd_ = ppd;
}

void SaccadeModel::reset() {
  recent_.clear();
  has_last_ = false;
}

glm::vec2 SaccadeModel::next(const std::vector<Corner>& corners, glm::ivec2 size, bool* skipped) {
  if (skipped) *skipped = false;
  const glm::vec2 centre = 0.5f * glm::vec2(size);
  if (has_last_ && params_.skip_probability > 0 && uniform() < params_.skip_probability) {
    if (skipped) *skipped = true;
    return last_;
  }
  std::vector<double> weight(corners.size(), 0.0);
  double total = 0;
  const double max_px = params_.max_amplitude_deg * ppd_, min_px = params_.min_distance_deg * ppd_;
  for (size_t i = 0; i < corners.size(); ++i) {
    const glm::vec2 p = corners[i].px;
    double w = std::max(0.0f, corners[i].score);
    if (!has_last_) {
      const glm::dvec2 d = glm::dvec2(p - centre) / (params_.centre_sigma * glm::dvec2(size));
      w *= std::exp(-0.5 * glm::dot(d, d));
    } else {
      if (glm::length(p - last_) > max_px) continue;
      bool too_close = false;
      for (const glm::vec2& r : recent_) too_close |= glm::length(p - r) < min_px;
      if (too_close) continue;
    }
    weight[i] = w;
    total += w;
  }
  glm::vec2 chosen = has_last_ ? last_ : centre;
  if (total > 0) {
    double u = uniform() * total;
    size_t i = 0;
    for (; i + 1 < corners.size() && u >= weight[i]; ++i) u -= weight[i];
    while (weight[i] == 0 && i > 0) --i;  // rounding at the end of the list
    chosen = corners[i].px;
  } else if (skipped) {
    *skipped = has_last_;  // nowhere to go: stay
  }
  last_ = chosen;
  has_last_ = true;
  recent_.push_back(chosen);
  while (static_cast<int>(recent_.size()) > params_.recent) recent_.pop_front();
  return chosen;
}

}  // namespace foveal
