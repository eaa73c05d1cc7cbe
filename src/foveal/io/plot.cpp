// foveal/io/plot.cpp — see plot.h.
#include "foveal/io/plot.h"

#include "foveal/util/error.h"
#include "foveal/util/files.h"

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace foveal {
namespace {

std::string svg_colour(glm::vec3 c) { return fmt::format("#{:02x}{:02x}{:02x}", int(c.r * 255), int(c.g * 255), int(c.b * 255)); }

}  // namespace

glm::u8vec3 heat_colour(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  // Piecewise-linear through five stops
  static const glm::vec3 stops[5] = {
      {0.05f, 0.05f, 0.35f}, {0.0f, 0.45f, 0.9f}, {0.1f, 0.85f, 0.85f}, {1.0f, 0.9f, 0.1f}, {0.9f, 0.1f, 0.05f}};
  const float s = t * 4;
  const int k = std::min(static_cast<int>(s), 3);
  const glm::vec3 c = glm::mix(stops[k], stops[k + 1], s - k);
  return glm::u8vec3(glm::round(c * 255.0f));
}

const std::vector<std::string>& plot_extensions() {
  static const std::vector<std::string> all = {".png", ".svg"};
  return all;
}

void save_plot(const Plot& plot, const std::string& path) {
  check_not_an_input(path);
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".svg") {
    std::ofstream out(path);
    if (!out) fail("{}: cannot open for writing", path);
    out << fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" font-family=\"sans-serif\">\n"
        "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
        plot.width, plot.height);
    for (const auto& s : plot.strokes) {
      std::string pts;
      for (auto p : s.points) pts += fmt::format("{:.1f},{:.1f} ", p.x, p.y);
      out << fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{}\"{} points=\"{}\"/>\n", svg_colour(s.colour), s.width,
                         s.dashed ? " stroke-dasharray=\"6,4\"" : "", pts);
    }
    for (const auto& l : plot.labels)
      out << fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"{}\"{}>{}</text>\n", l.at.x, l.at.y, l.size,
                         l.centred ? " text-anchor=\"middle\"" : "", l.text);
    out << "</svg>\n";
    if (!out) fail("{}: write failed", path);
    return;
  }
  if (ext != ".png") fail("{}: plots are written as .svg or .png", path);
  cv::Mat mat(plot.height, plot.width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (const auto& s : plot.strokes) {
    const cv::Scalar c(s.colour.b * 255, s.colour.g * 255, s.colour.r * 255);
    for (size_t k = 1; k < s.points.size(); ++k) {
      if (s.dashed && (k / 3) % 2 == 1) continue;
      cv::line(mat, {int(s.points[k - 1].x), int(s.points[k - 1].y)}, {int(s.points[k].x), int(s.points[k].y)}, c, int(s.width),
               cv::LINE_AA);
    }
  }
  for (const auto& l : plot.labels) {
    const double scale = l.size / 30.0;
    int baseline = 0;
    const cv::Size size = cv::getTextSize(l.text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    const int x = l.centred ? int(l.at.x) - size.width / 2 : int(l.at.x);
    cv::putText(mat, l.text, {x, int(l.at.y)}, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  if (!cv::imwrite(path, mat)) fail("{}: cannot write image (does the folder exist?)", path);
}

}  // namespace foveal
