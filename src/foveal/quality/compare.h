// foveal/quality/compare.h — image quality of a foveated render against a reference: RMSE,
// PSNR and SSIM over the whole image and per eccentricity band around the gaze, with the bands
// in degrees of visual angle from the same eccentricity function the renderer uses.
//
// SSIM is Wang et al. (2004): 11×11 Gaussian window of σ = 1.5, K1 = 0.01, K2 = 0.03, dynamic
// range L = 1, computed on each colour channel and averaged; a band's SSIM is the mean of the
// SSIM map over its pixels. Near the border the window leaves the image: by default (`reflect`)
// the image is mirrored there (OpenCV's BORDER_REFLECT_101) and every pixel has an SSIM; `valid`
// is the convention of Wang et al.'s reference code and scikit-image — only pixels whose whole
// window lies inside the image (5 px from every edge) count, the others are NaN in the map. PSNR uses a peak of 1 (images as stored: sRGB PNG values in [0, 1], or
// linear floats from PFM/EXR). A second reference rendered with another seed measures the
// reference's own Monte-Carlo noise: each band's error is also given as a multiple of it.
#pragma once

#include "foveal/perception/foveation.h"
#include "foveal/util/image.h"

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

// Errors over a set of pixels.
struct ErrorStats {
  size_t pixels = 0;
  size_t ssim_pixels = 0;  // pixels with an SSIM (fewer than `pixels` near the border with SsimBorder::valid)
  double mse = 0;          // mean over pixels and channels of (a − b)²
  double rmse = 0;
  double psnr = std::numeric_limits<double>::infinity();  // 10·log10(1/mse) dB; inf when identical
  double ssim = 1;                                        // mean of the SSIM map over the pixels that have one (NaN when none has)
  double rmse_rel_se = 0;                                 // standard error of the RMSE over these pixels, relative to it
};

// A region of the image: an eccentricity range [lo, hi) in degrees, or the q(E) = 1 region.
struct Band {
  std::string name;
  double lo_deg = 0, hi_deg = 0;  // hi = inf for the last band
  bool foveal_region = false;     // the pixels with q(E) = 1 (the elliptical model), not a range
};
// 0–2.5, 2.5–5, 5–10, 10–20, 20+ degrees, and q(E) = 1.
std::vector<Band> default_bands();

struct BandResult {
  Band band;
  ErrorStats error;                 // a against b
  std::optional<ErrorStats> noise;  // the reference against the second reference
  double noise_ratio = 0;           // error.rmse / noise.rmse (0 without a second reference)
  double ratio_se = 0;              // its standard error
  bool within_noise = false;        // noise_ratio ≤ 1 + 2·ratio_se: indistinguishable from the reference's own noise
};

struct Comparison {
  int width = 0, height = 0;
  glm::dvec2 gaze_px{0};
  ErrorStats whole;
  std::optional<ErrorStats> whole_noise;
  std::vector<BandResult> bands;
  std::vector<float> ssim_map;              // per pixel, mean over channels
  std::vector<float> abs_error;             // per pixel |a − b|, mean over channels
  std::vector<double> squared_error;        // per pixel (a − b)², mean over channels
  std::vector<double> noise_squared_error;  // per pixel (b2 − b)² (empty without a second reference)
  std::vector<float> eccentricity_deg;      // per pixel, the renderer's exact angle from the gaze
  std::vector<uint8_t> foveal;              // per pixel: q(E) = 1
  std::vector<float> quality;               // per pixel q(E), the renderer's normalised acuity
  // Acuity-weighted RMSE: sqrt(Σ q² · e² / Σ q²). An error counts in proportion to the resolvable
  // cells per unit area where it lies (∝ f_c², the reasoning behind γ = 2): one number for the
  // error a viewer fixating the gaze point can see. The same for the second reference when given.
  double weighted_rmse = 0;
  double weighted_noise_rmse = 0;  // 0 without a second reference
  double weighted_ratio() const { return weighted_noise_rmse > 0 ? weighted_rmse / weighted_noise_rmse : 0.0; }
};

enum class SsimBorder { reflect, valid };
const char* to_string(SsimBorder border);
SsimBorder parse_ssim_border(const std::string& name);  // throws Error for an unknown name

// The per-pixel SSIM map (mean over channels) of two images of the same size; with `valid` the
// pixels closer than 5 px to an edge are NaN (no SSIM).
std::vector<float> ssim_map(const Image& a, const Image& b, SsimBorder border = SsimBorder::reflect);

// Compare `a` with the reference `b` (and optionally a second reference `b2` of another seed).
// The images must have the same size and channels; throws Error otherwise.
Comparison compare_images(const Image& a, const Image& b, const Image* b2, const Display& display, glm::dvec2 gaze_px,
                          const FoveationParams& params, const std::vector<Band>& bands = default_bands(),
                          SsimBorder ssim_border = SsimBorder::reflect);

// The per-pixel part of the reference's noise — (b2 − b)² and SSIM(b2, b) — which depends on
// neither the judged image nor the gaze: computed once, it serves every comparison against `b`.
struct ReferenceNoise {
  std::vector<double> squared_error;  // per pixel, mean over channels
  std::vector<float> ssim;            // per pixel, mean over channels
};
ReferenceNoise reference_noise(const Image& b2, const Image& b, SsimBorder ssim_border = SsimBorder::reflect);
// The same comparison with the reference's noise already computed.
// (`ssim_border` must be the one the noise was computed with.)
Comparison compare_images(const Image& a, const Image& b, const ReferenceNoise& noise, const Display& display, glm::dvec2 gaze_px,
                          const FoveationParams& params, const std::vector<Band>& bands = default_bands(),
                          SsimBorder ssim_border = SsimBorder::reflect);

// sqrt(Σ q²·e² / Σ q²) of a against b with the given per-pixel q (a Comparison's `quality`):
// the acuity-weighted RMSE alone, without the maps and SSIM of a whole comparison.
double acuity_weighted_rmse(const Image& a, const Image& b, const std::vector<float>& quality);

// The per-band table (pixels, RMSE, PSNR, SSIM, and with a second reference the noise RMSE, the
// ratio and the verdict) as Markdown, with the acuity-weighted RMSE below it.
std::string comparison_markdown(const Comparison& c);

// Every figure of a comparison as JSON (the `compare --json` document without the file names):
// size, gaze, display, whole, per band, the acuity-weighted RMSE; infinities as "inf".
nlohmann::json comparison_json(const Comparison& c, const Display& display);

// |a − b| per pixel as a heat-map image (linear RGB), scaled so that `full_scale` is the hottest.
Image error_map_image(const Comparison& c, float full_scale);
// RMSE in 1° eccentricity bins against eccentricity (.png or .svg); with the noise floor where known.
void write_error_plot(const Comparison& c, const std::string& path);

}  // namespace foveal
