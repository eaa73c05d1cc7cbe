// foveal/vision/features.h — fixation candidates: FAST-9 corners of the rendered image (OpenCV),
// and the simulated saccades that choose among them.
#pragma once

#include "foveal/util/image.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <deque>
#include <random>
#include <vector>

namespace foveal {

struct Corner {
  glm::vec2 px{0};  // pixel centre, render pixels
  float score = 0;  // FAST response
};

// The 8-bit luma OpenCV's FAST sees: linear RGB → sRGB → BT.601 grey (cv::cvtColor).
std::vector<uint8_t> grey_8bit(const Image& linear_rgb);
// FAST-9 corners (cv::FAST, TYPE_9_16) of a linear RGB image.
std::vector<Corner> detect_corners(const Image& linear_rgb, int threshold = 20, bool nonmax_suppression = true);
// The table grey_8bit() maps a linear value through: entry k is the sRGB byte of k / 4096 (the
// value clamped to [0, 1], index value·4096 + 0.5); the GPU uploads the same 4097 bytes.
const std::vector<uint8_t>& srgb8_table();
// The same corners from the per-pixel functions the GPU runs (vision/fast.h), on the CPU: the
// test that holds them, and so the GPU's corners, to OpenCV's. Without suppression the score
// is still the response (OpenCV reports 0 there).
std::vector<Corner> fast_corners(const std::vector<uint8_t>& grey, int width, int height, int threshold = 20,
                                 bool nonmax_suppression = true);

// Simulated saccades (DESIGN.md "Focus selection"): the first fixation ∝ score × a bivariate
// Gaussian around the image centre; each next one ∝ score among corners within the maximum
// amplitude of the current fixation and at least the minimum distance from the recent ones.
struct SaccadeParams {
  double centre_sigma = 0.25;     // first fixation: Gaussian σ as a fraction of the image size
  double max_amplitude_deg = 15;  // furthest next fixation, degrees of visual angle
  double min_distance_deg = 2;    // nearest allowed to the recent fixations, degrees
  int recent = 8;                 // how many recent fixations keep their distance
  double skip_probability = 0;    // chance to keep the last fixation (glaucoma)
};

class SaccadeModel {
 public:
  SaccadeModel(const SaccadeParams& params, double pixels_per_degree, uint64_t seed);
  // The next fixation among `corners` (image `size`); reuses the last one when skipping or when
  // no corner qualifies. `skipped` says whether this step kept the last fixation on purpose.
  glm::vec2 next(const std::vector<Corner>& corners, glm::ivec2 size, bool* skipped = nullptr);
  // Forget the recent fixations (e.g. when the camera moved).
  void reset();
  // The image's pixels per degree (the amplitude limits are in degrees).
  void set_pixels_per_degree(double ppd);
  const std::deque<glm::vec2>& recent() const { return recent_; }

 private:
  SaccadeParams params_;
  double ppd_;
  std::mt19937_64 rng_;
  std::deque<glm::vec2> recent_;
  bool has_last_ = false;
  glm::vec2 last_{0};
  double uniform();
};

}  // namespace foveal
