// foveal/render/pull_push.cpp — pull-push's push, with OpenCV's bilinear upsampling.
#include "foveal/render/pull_push.h"

#include <opencv2/imgproc.hpp>

namespace foveal {

void PullPush::prepare(int width, int height) {
  pixels_size_ = Size{width, height};
  sizes_.assign(1, Size{(width + 1) / 2, first_rows(height)});
  while (sizes_.back().width > 1 || sizes_.back().height > 1)
    sizes_.push_back(Size{(sizes_.back().width + 1) / 2, (sizes_.back().height + 1) / 2});
  const size_t levels = sizes_.size();
  sum_.resize(levels);
  cover_.resize(levels);
  estimate_.resize(levels);
  for (size_t l = 0; l < levels; ++l) {
    const size_t cells = static_cast<size_t>(sizes_[l].width) * static_cast<size_t>(sizes_[l].height);
    sum_[l].resize(cells);
    cover_[l].resize(cells);
    estimate_[l].resize(cells);
  }
  pixels_.resize(static_cast<size_t>(width) * static_cast<size_t>(height));
}

void PullPush::pull_levels() {
  // Each coarser level from the level below
  for (size_t l = 1; l < sizes_.size(); ++l) {
    const std::vector<float>&s = sum_[l - 1], &c = cover_[l - 1];
    pull_level(
        sizes_[l - 1].width, sizes_[l - 1].height,
        [&](size_t i) {
          return std::pair{s[i], c[i]};
        },
        sizes_[l], sum_[l].data(), cover_[l].data(), 0, sizes_[l].height);
  }
}

bool PullPush::push() {
  // The coarsest cell's mean, then at each finer level a cell's own mean in proportion to its
  // weight, the coarser estimate (upsampled bilinearly) for the rest
  const size_t top = sizes_.size() - 1;
  if (!(cover_[top][0] > 0)) return false;  // nothing known
  estimate_[top][0] = sum_[top][0] / cover_[top][0];
  for (size_t l = top; l-- > 0;) {
    const cv::Size coarse(sizes_[l + 1].width, sizes_[l + 1].height), fine(sizes_[l].width, sizes_[l].height);
    cv::Mat estimate(fine, CV_32F, estimate_[l].data());
    cv::resize(cv::Mat(coarse, CV_32F, estimate_[l + 1].data()), estimate, fine, 0, 0, cv::INTER_LINEAR);
    std::vector<float>& e = estimate_[l];
    for (size_t i = 0; i < e.size(); ++i) e[i] = sum_[l][i] + std::max(0.0f, 1.0f - cover_[l][i]) * e[i];
  }
  // The pixels: the first level's estimates, bilinearly at each pixel's centre
  const cv::Size first(sizes_[0].width, sizes_[0].height), full(pixels_size_.width, pixels_size_.height);
  cv::Mat pixels(full, CV_32F, pixels_.data());
  cv::resize(cv::Mat(first, CV_32F, estimate_[0].data()), pixels, full, 0, 0, cv::INTER_LINEAR);
  return true;
}

}  // namespace foveal
