// foveal/io/scanpath.cpp — scan-path pictures with OpenCV's drawing functions.
#include "foveal/io/scanpath.h"

#include "foveal/io/image_io.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace foveal {

void write_scanpath(const Recording& r, const FixationResult& result, const std::string& path, const ScanpathStyle& style) {
  check_not_an_input(path);
  const glm::dvec2 screen(std::max(1, r.screen_px.x), std::max(1, r.screen_px.y));
  const double scale = std::min(1.0, style.max_width / screen.x);
  const int margin = 24;
  const cv::Size size(static_cast<int>(screen.x * scale) + 2 * margin, static_cast<int>(screen.y * scale) + 2 * margin);
  cv::Mat canvas(size, CV_8UC3, cv::Scalar(38, 34, 32));
  auto at = [&](glm::dvec2 p) { return cv::Point(int(std::lround(margin + p.x * scale)), int(std::lround(margin + p.y * scale))); };
  const int shift = 0;
  // Screen
  cv::rectangle(canvas, at({0, 0}), at(screen), cv::Scalar(70, 64, 60), cv::FILLED);
  cv::rectangle(canvas, at({0, 0}), at(screen), cv::Scalar(140, 130, 120), 1);
  // Raw gaze trace (valid samples, consecutive ones joined)
  cv::Mat trace = canvas.clone();
  const GazeSample* prev = nullptr;
  for (const GazeSample& s : r.samples) {
    if (!s.valid) {
      prev = nullptr;
      continue;
    }
    if (prev && s.t_s - prev->t_s < 0.1) cv::line(trace, at(prev->px), at(s.px), cv::Scalar(160, 200, 120), 1, cv::LINE_AA, shift);
    prev = &s;
  }
  cv::addWeighted(trace, 0.35, canvas, 0.65, 0, canvas);
  // Fixations: circle area ∝ duration; lines between consecutive ones
  const auto& fx = result.fixations;
  double longest = 0;
  for (const Fixation& f : fx) longest = std::max(longest, f.duration_s());
  const double max_radius = std::max(6.0, 0.035 * std::min(size.width, size.height));
  auto radius = [&](const Fixation& f) {
    return std::max(2, int(std::lround(max_radius * std::sqrt(std::max(0.0, f.duration_s()) / std::max(longest, 1e-9)))));
  };
  for (size_t k = 1; k < fx.size(); ++k) cv::line(canvas, at(fx[k - 1].px), at(fx[k].px), cv::Scalar(200, 200, 200), 1, cv::LINE_AA);
  cv::Mat fill = canvas.clone();
  for (const Fixation& f : fx) cv::circle(fill, at(f.px), radius(f), cv::Scalar(60, 170, 255), cv::FILLED, cv::LINE_AA);
  cv::addWeighted(fill, 0.45, canvas, 0.55, 0, canvas);
  for (const Fixation& f : fx) cv::circle(canvas, at(f.px), radius(f), cv::Scalar(60, 170, 255), 1, cv::LINE_AA);
  if (style.numbers)
    for (size_t k = 0; k < fx.size() && k < 99; ++k)
      cv::putText(canvas, std::to_string(k + 1), at(fx[k].px) + cv::Point(-4, 4), cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(255, 255, 255),
                  1, cv::LINE_AA);
  // Title and scale
  if (!style.title.empty())
    cv::putText(canvas, style.title, {margin, margin - 8}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  const std::string legend =
      fmt::format("{}x{} px screen; circle area ~ fixation duration (longest {:.0f} ms)", r.screen_px.x, r.screen_px.y, longest * 1000);
  cv::putText(canvas, legend, {margin, size.height - 8}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(200, 200, 200), 1, cv::LINE_AA);
  bool written = false;
  try {
    written = cv::imwrite(path, canvas);
  } catch (const cv::Exception&) {
    written = false;
  }
  if (!written) fail("{}: cannot write image (does the folder exist, and is the extension .png?)", path);
}

void write_fixation_picture(const Image& img, const std::vector<glm::vec2>& fixations, const std::vector<glm::vec2>& corners,
                            const std::string& path) {
  cv::Mat canvas(img.height, img.width, CV_8UC3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) canvas.at<cv::Vec3b>(y, x)[2 - c] = srgb_byte(img.at(x, y, std::min(c, img.channels - 1)));
  auto at = [](glm::vec2 p) { return cv::Point(int(std::lround(p.x)), int(std::lround(p.y))); };
  for (const glm::vec2& c : corners) cv::circle(canvas, at(c), 1, cv::Scalar(0, 215, 255), cv::FILLED);
  const int radius = std::max(4, std::min(img.width, img.height) / 60);
  for (size_t k = 1; k < fixations.size(); ++k)
    cv::line(canvas, at(fixations[k - 1]), at(fixations[k]), cv::Scalar(40, 200, 40), 1, cv::LINE_AA);
  for (size_t k = 0; k < fixations.size(); ++k)
    cv::circle(canvas, at(fixations[k]), k == 0 ? radius + 3 : radius, cv::Scalar(40, 220, 40), k == 0 ? 3 : 2, cv::LINE_AA);
  bool written = false;
  try {
    written = cv::imwrite(path, canvas);
  } catch (const cv::Exception&) {}
  if (!written) fail("{}: cannot write image (does the folder exist, and is the extension .png?)", path);
}

}  // namespace foveal
