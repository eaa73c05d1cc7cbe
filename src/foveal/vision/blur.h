// foveal/vision/blur.h — per-pixel variable Gaussian blur (the paper's depth-of-field filter).
//
// Each pixel gathers taps distributed over its own circle of confusion (a fixed pattern of
// points in the unit disc, scaled by the pixel's CoC radius, read with bilinear filtering from
// the image or, for widely spaced taps, a pre-averaged lower-resolution copy),
// weighted by a bivariate Gaussian whose σ is a third of the CoC radius (σ = diameter / 6, so
// the disc holds ±3σ). The kernel differs per pixel, so it is not separable. Weights are
// normalised: a constant image stays constant. Scatter-aware (default): a tap whose own CoC does
// not reach the pixel is left out, so a sharp object does not bleed into a blurred background
// around it — what the thin-lens reference shows (`bench blur` measures both).
#pragma once

#include "foveal/util/image.h"
#include "foveal/vision/blur_kernel.h"

#include <glm/glm.hpp>

#include <vector>

namespace foveal {

struct BlurParams {
  int taps = 64;               // most points of a disc pattern (plus the centre), for large CoCs
  float max_diameter_px = 96;  // CoCs are clamped to this diameter (unseen cells, far defocus)
  bool scatter_aware = true;   // a tap counts only if its own CoC reaches the pixel (no sharp-edge bleeding)
};

// taps_for_diameter(d, max_taps), the taps of a CoC of d pixels, is in blur_kernel.h with the
// per-pixel gather both backends run. Taps spaced wider than two pixels read a half-, quarter-, …
// resolution copy of the image (2×2 box averages).

// The unit-disc tap pattern (Vogel spiral) with its Gaussian weights (σ = 1/3 of the radius).
struct TapPattern {
  std::vector<glm::vec2> offset;  // in the unit disc; offset[0] is the centre
  std::vector<float> weight;      // exp(−|o|²·9/2), not normalised
};
TapPattern make_tap_pattern(int taps);
// The patterns of min(8, max_taps) … max_taps taps end to end, as the gather reads them.
struct TapTable {
  std::vector<glm::vec2> offsets;
  std::vector<float> weights;
  std::vector<int> start;  // pattern of n taps at start[n − first_count]
  int first_count = 0, max_taps = 0;
};
TapTable make_tap_table(int max_taps);
// An elliptical CoC's axes in image coordinates (y down) for an axis angle in degrees.
void ellipse_axes(float axis_deg, glm::vec2* along, glm::vec2* across);

// Elliptical CoCs (astigmatism): per pixel, the diameters along and across an axis as fractions
// of the pixel's CoC diameter (the larger is 1), and the axis angle in degrees (0 = horizontal,
// counter-clockwise as the viewer sees the image).
struct CocShape {
  std::vector<glm::vec2> scale;  // (along, across) ≤ 1
  float axis_deg = 0;
};

// Blur `image` with a CoC diameter per pixel (render pixels; 0 = sharp), round or elliptical.
Image variable_blur(const Image& image, const std::vector<float>& coc_diameter_px, const BlurParams& params = {},
                    const CocShape* shape = nullptr);

}  // namespace foveal
