// foveal/impair/field_picture.cpp — the loss map drawn with OpenCV.
#include "foveal/impair/field_picture.h"

#include "foveal/util/error.h"
#include "foveal/util/files.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace foveal {

void write_field_picture(const VisualField& field, const FieldMap& map, const std::string& path) {
  check_not_an_input(path);
  constexpr int kSize = 600;
  constexpr double kPpd = 10, kHalf = 30;
  cv::Mat img(kSize, kSize, CV_8UC3);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const double fx = (x + 0.5) / kPpd - kHalf, fy = kHalf - (y + 0.5) / kPpd;
      const auto v = static_cast<uint8_t>(std::lround(255 * (1 - std::min(map.loss_db(fx, fy), 30.0) / 30.0)));
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(v, v, v);
    }
  const cv::Scalar axis(200, 120, 40);  // BGR
  cv::line(img, {kSize / 2, 0}, {kSize / 2, kSize - 1}, axis, 1);
  cv::line(img, {0, kSize / 2}, {kSize - 1, kSize / 2}, axis, 1);
  for (int r : {10, 20, 30}) cv::circle(img, {kSize / 2, kSize / 2}, static_cast<int>(r * kPpd), axis, 1, cv::LINE_AA);
  // the view's test locations (both eyes: the integrated field), green (no loss) → red (30 dB)
  for (const FieldPoint& p : field.view_points()) {
    const cv::Point c(static_cast<int>(std::lround((p.x_deg + kHalf) * kPpd)), static_cast<int>(std::lround((kHalf - p.y_deg) * kPpd)));
    const double t = std::clamp(p.loss_db / 30.0, 0.0, 1.0);
    cv::circle(img, c, 6, cv::Scalar(40, 255 * (1 - t), 255 * t), cv::FILLED, cv::LINE_AA);
    cv::circle(img, c, 6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  cv::putText(img, "view " + field.resolved_view() + ", +-30 deg, white 0 dB .. black 30 dB loss", {8, kSize - 10},
              cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(40, 40, 220), 1, cv::LINE_AA);
  bool ok = false;
  try {
    ok = cv::imwrite(path, img);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) fail("{}: cannot write the field picture", path);
}

}  // namespace foveal
