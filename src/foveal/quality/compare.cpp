// foveal/quality/compare.cpp — see compare.h.
#include "foveal/quality/compare.h"

#include "foveal/io/plot.h"
#include "foveal/util/error.h"

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace foveal {

std::vector<Band> default_bands() {
  const double inf = std::numeric_limits<double>::infinity();
  return {{"0-2.5", 0, 2.5, false}, {"2.5-5", 2.5, 5, false}, {"5-10", 5, 10, false},
          {"10-20", 10, 20, false}, {"20+", 20, inf, false},  {"q=1", 0, 0, true}};
}

namespace {

void check_same(const Image& a, const Image& b, const char* what) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    fail("compare: {} is {}x{}x{}, the reference {}x{}x{}: the images must have the same size and channels", what, a.width, a.height,
         a.channels, b.width, b.height, b.channels);
  if (a.empty()) fail("compare: empty image");
  // NaN or infinite values make every error NaN, and a NaN error would read as "identical" (PSNR inf)
  auto non_finite = [](const Image& im) {
    return std::count_if(im.pixels.begin(), im.pixels.end(), [](float v) { return !std::isfinite(v); });
  };
  if (const auto n = non_finite(a)) fail("compare: {} has {} NaN or infinite values; errors need finite pixels", what, n);
  if (const auto n = non_finite(b)) fail("compare: the reference has {} NaN or infinite values; errors need finite pixels", n);
}

cv::Mat channel(const Image& img, int c) {
  cv::Mat m(img.height, img.width, CV_64F);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) m.at<double>(y, x) = img.at(x, y, c);
  return m;
}

// Per-pixel squared and absolute errors (means over channels), in one pass.
void pixel_errors(const Image& a, const Image& b, std::vector<double>& squared, std::vector<float>* absolute) {
  const size_t n = static_cast<size_t>(a.width) * a.height;
  squared.resize(n);
  if (absolute) absolute->resize(n);
  for (size_t i = 0; i < n; ++i) {
    double sq = 0, ab = 0;
    for (int c = 0; c < a.channels; ++c) {
      const double d = static_cast<double>(a.pixels[i * a.channels + c]) - b.pixels[i * a.channels + c];
      sq += d * d;
      ab += std::abs(d);
    }
    squared[i] = sq / a.channels;
    if (absolute) (*absolute)[i] = static_cast<float>(ab / a.channels);
  }
}

struct Accumulator {
  size_t pixels = 0, ssim_pixels = 0;
  double se = 0, se_sq = 0, ssim = 0;
  ErrorStats stats() const {
    ErrorStats s;
    s.pixels = pixels;
    if (pixels == 0) return s;
    s.mse = se / pixels;
    s.rmse = std::sqrt(s.mse);
    s.psnr = s.mse > 0 ? 10 * std::log10(1.0 / s.mse) : std::numeric_limits<double>::infinity();
    s.ssim_pixels = ssim_pixels;
    s.ssim = ssim_pixels > 0 ? ssim / ssim_pixels : std::numeric_limits<double>::quiet_NaN();
    // Standard error of the RMSE, relative: ½ · sd(se) / (mean(se)·√n)
    const double var = std::max(0.0, se_sq / pixels - s.mse * s.mse);
    s.rmse_rel_se = s.mse > 0 ? 0.5 * std::sqrt(var / pixels) / s.mse : 0.0;
    return s;
  }
};

bool in_band(const Band& band, double ecc_deg, bool foveal) {
  return band.foveal_region ? foveal : ecc_deg >= band.lo_deg && ecc_deg < band.hi_deg;
}

}  // namespace

const char* to_string(SsimBorder border) { return border == SsimBorder::valid ? "valid" : "reflect"; }

SsimBorder parse_ssim_border(const std::string& name) {
  if (name == "reflect") return SsimBorder::reflect;
  if (name == "valid") return SsimBorder::valid;
  fail("ssim_border: unknown convention '{}' (known: reflect, valid)", name);
}

std::vector<float> ssim_map(const Image& a, const Image& b, SsimBorder border) {
  check_same(a, b, "the image");
  const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;  // (K1·L)², (K2·L)², L = 1
  const cv::Size window(11, 11);
  const double sigma = 1.5;
  cv::Mat sum = cv::Mat::zeros(a.height, a.width, CV_64F);
  for (int c = 0; c < a.channels; ++c) {
    const cv::Mat x = channel(a, c), y = channel(b, c);
    cv::Mat mx, my, sxx, syy, sxy;
    cv::GaussianBlur(x, mx, window, sigma);
    cv::GaussianBlur(y, my, window, sigma);
    cv::GaussianBlur(x.mul(x), sxx, window, sigma);
    cv::GaussianBlur(y.mul(y), syy, window, sigma);
    cv::GaussianBlur(x.mul(y), sxy, window, sigma);
    const cv::Mat mxx = mx.mul(mx), myy = my.mul(my), mxy = mx.mul(my);
    sxx -= mxx;
    syy -= myy;
    sxy -= mxy;
    const cv::Mat num = (2 * mxy + c1).mul(2 * sxy + c2), den = (mxx + myy + c1).mul(sxx + syy + c2);
    cv::Mat s;
    cv::divide(num, den, s);
    sum += s;
  }
  std::vector<float> out(static_cast<size_t>(a.width) * a.height);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) out[static_cast<size_t>(y) * a.width + x] = static_cast<float>(sum.at<double>(y, x) / a.channels);
  if (border == SsimBorder::valid) {  // only windows wholly inside the image (Wang et al.'s 'valid' filtering)
    const int r = window.width / 2;
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x)
        if (x < r || y < r || x >= a.width - r || y >= a.height - r) out[static_cast<size_t>(y) * a.width + x] = NAN;
  }
  return out;
}

ReferenceNoise reference_noise(const Image& b2, const Image& b, SsimBorder ssim_border) {
  check_same(b2, b, "the second reference");
  ReferenceNoise noise;
  pixel_errors(b2, b, noise.squared_error, nullptr);
  noise.ssim = ssim_map(b2, b, ssim_border);
  return noise;
}

double acuity_weighted_rmse(const Image& a, const Image& b, const std::vector<float>& quality) {
  check_same(a, b, "the image");
  if (quality.size() != static_cast<size_t>(a.width) * a.height)
    fail("acuity_weighted_rmse: {} q values for {}x{} pixels", quality.size(), a.width, a.height);
  std::vector<double> se;
  pixel_errors(a, b, se, nullptr);
  double w_sum = 0, w_se = 0;
  for (size_t i = 0; i < se.size(); ++i) {
    const double w = static_cast<double>(quality[i]) * quality[i];
    w_sum += w;
    w_se += w * se[i];
  }
  return w_sum > 0 ? std::sqrt(w_se / w_sum) : 0.0;
}

namespace {

// The comparison, with the reference's noise maps or without (nullptr).
Comparison compare(const Image& a, const Image& b, const ReferenceNoise* noise, const Display& display, glm::dvec2 gaze_px,
                   const FoveationParams& params, const std::vector<Band>& bands, SsimBorder ssim_border) {
  check_same(a, b, "the image");
  const size_t pixels = static_cast<size_t>(a.width) * a.height;
  if (noise && (noise->squared_error.size() != pixels || noise->ssim.size() != pixels))
    fail("compare: the reference's noise maps are not of the image's size");
  const bool b2 = noise != nullptr;
  Comparison c;
  c.width = a.width;
  c.height = a.height;
  c.gaze_px = gaze_px;
  const size_t n = static_cast<size_t>(a.width) * a.height;
  // The renderer's eccentricity and q(E) at every pixel
  const FoveationModel model(display, a.width, a.height, gaze_px, params);
  c.eccentricity_deg.resize(n);
  c.foveal.resize(n);
  c.quality.resize(n);
  tbb::parallel_for(0, a.height, [&](int y) {
    for (int x = 0; x < a.width; ++x) {
      const FoveaSample f = model.evaluate(x, y);
      c.eccentricity_deg[static_cast<size_t>(y) * a.width + x] = static_cast<float>(f.angle_deg);
      c.foveal[static_cast<size_t>(y) * a.width + x] = f.quality >= 1.0 - 1e-12;
      c.quality[static_cast<size_t>(y) * a.width + x] = static_cast<float>(f.quality);
    }
  });
  pixel_errors(a, b, c.squared_error, &c.abs_error);
  c.ssim_map = ssim_map(a, b, ssim_border);
  const std::vector<double>& se = c.squared_error;
  if (b2) c.noise_squared_error = noise->squared_error;
  const std::vector<double>& se2 = c.noise_squared_error;
  static const std::vector<float> no_ssim;
  const std::vector<float>& ssim2 = b2 ? noise->ssim : no_ssim;
  Accumulator whole, whole_noise;
  std::vector<Accumulator> acc(bands.size()), noise_acc(bands.size());
  double w_sum = 0, w_se = 0, w_se2 = 0;
  for (size_t i = 0; i < n; ++i) {
    const double w = static_cast<double>(c.quality[i]) * c.quality[i];
    w_sum += w;
    w_se += w * se[i];
    if (b2) w_se2 += w * se2[i];
    auto add = [&](Accumulator& t, bool second) {
      ++t.pixels;
      const double v = second ? se2[i] : se[i];
      t.se += v;
      t.se_sq += v * v;
      const float ssim = second ? ssim2[i] : c.ssim_map[i];
      if (std::isfinite(ssim)) {
        t.ssim += ssim;
        ++t.ssim_pixels;
      }
    };
    add(whole, false);
    if (b2) add(whole_noise, true);
    for (size_t k = 0; k < bands.size(); ++k)
      if (in_band(bands[k], c.eccentricity_deg[i], c.foveal[i])) {
        add(acc[k], false);
        if (b2) add(noise_acc[k], true);
      }
  }
  c.whole = whole.stats();
  if (b2) c.whole_noise = whole_noise.stats();
  c.weighted_rmse = w_sum > 0 ? std::sqrt(w_se / w_sum) : 0.0;
  c.weighted_noise_rmse = w_sum > 0 ? std::sqrt(w_se2 / w_sum) : 0.0;
  for (size_t k = 0; k < bands.size(); ++k) {
    BandResult r;
    r.band = bands[k];
    r.error = acc[k].stats();
    if (b2) {
      r.noise = noise_acc[k].stats();
      r.noise_ratio = r.noise->rmse > 0 ? r.error.rmse / r.noise->rmse : (r.error.rmse > 0 ? std::numeric_limits<double>::infinity() : 0.0);
      // Within the noise: the ratio is not above 1 by more than twice its standard error
      r.ratio_se = r.noise_ratio * std::hypot(r.error.rmse_rel_se, r.noise->rmse_rel_se);
      r.within_noise = r.error.pixels > 0 && r.noise_ratio <= 1.0 + 2.0 * r.ratio_se;
    }
    c.bands.push_back(r);
  }
  return c;
}

}  // namespace

std::string comparison_markdown(const Comparison& c) {
  const bool b2 = c.whole_noise.has_value();
  auto psnr = [](double v) { return std::isfinite(v) ? fmt::format("{:.2f}", v) : std::string("inf"); };
  std::string out = b2 ? "| region | pixels | RMSE | PSNR (dB) | SSIM | reference noise RMSE | × noise | verdict |\n"
                         "|---|---:|---:|---:|---:|---:|---:|---|\n"
                       : "| region | pixels | RMSE | PSNR (dB) | SSIM |\n|---|---:|---:|---:|---:|\n";
  auto row = [&](const std::string& name, const ErrorStats& s, const BandResult* r) {
    out += fmt::format("| {} | {} | {:.5f} | {} | {:.4f} |", name, s.pixels, s.rmse, psnr(s.psnr), s.ssim);
    if (b2 && r && r->noise && s.pixels > 0)
      out += fmt::format(" {:.5f} | {:.2f} ± {:.2f} | {} |", r->noise->rmse, r->noise_ratio, r->ratio_se,
                         r->within_noise ? "within noise" : "outside");
    else if (b2)
      out += fmt::format(" {} | | |", c.whole_noise && !r ? fmt::format("{:.5f}", c.whole_noise->rmse) : "");
    out += "\n";
  };
  row("whole image", c.whole, nullptr);
  for (const BandResult& r : c.bands) row(r.band.foveal_region ? "q(E) = 1" : r.band.name + "°", r.error, &r);
  out += fmt::format("\nAcuity-weighted RMSE (each pixel's squared error weighted by q(E)²): {:.5f}", c.weighted_rmse);
  if (b2) out += fmt::format("; the reference's own: {:.5f} (× {:.2f})", c.weighted_noise_rmse, c.weighted_ratio());
  return out + "\n";
}

Comparison compare_images(const Image& a, const Image& b, const Image* b2, const Display& display, glm::dvec2 gaze_px,
                          const FoveationParams& params, const std::vector<Band>& bands, SsimBorder ssim_border) {
  if (!b2) return compare(a, b, nullptr, display, gaze_px, params, bands, ssim_border);
  const ReferenceNoise noise = reference_noise(*b2, b, ssim_border);
  return compare(a, b, &noise, display, gaze_px, params, bands, ssim_border);
}

Comparison compare_images(const Image& a, const Image& b, const ReferenceNoise& noise, const Display& display, glm::dvec2 gaze_px,
                          const FoveationParams& params, const std::vector<Band>& bands, SsimBorder ssim_border) {
  return compare(a, b, &noise, display, gaze_px, params, bands, ssim_border);
}

Image error_map_image(const Comparison& c, float full_scale) {
  Image out(c.width, c.height, 3);
  for (size_t i = 0; i < c.abs_error.size(); ++i) {
    const glm::u8vec3 colour = heat_colour(full_scale > 0 ? c.abs_error[i] / full_scale : 0.0f);
    for (int k = 0; k < 3; ++k) out.pixels[i * 3 + k] = colour[k] / 255.0f;
  }
  return out;
}

void write_error_plot(const Comparison& c, const std::string& path) {
  // RMSE per 1° bin
  float max_ecc = 0;
  for (float e : c.eccentricity_deg) max_ecc = std::max(max_ecc, e);
  const int bins = std::max(1, static_cast<int>(std::ceil(max_ecc)));
  std::vector<double> se(bins, 0), se2(bins, 0);
  std::vector<size_t> count(bins, 0);
  const std::vector<double>& e = c.squared_error;
  const std::vector<double>& e2 = c.noise_squared_error;
  const bool b2 = !e2.empty();
  for (size_t i = 0; i < e.size(); ++i) {
    const int k = std::min(bins - 1, static_cast<int>(c.eccentricity_deg[i]));
    se[k] += e[i];
    if (b2) se2[k] += e2[i];
    ++count[k];
  }
  double top = 0;
  for (int k = 0; k < bins; ++k)
    if (count[k]) top = std::max({top, std::sqrt(se[k] / count[k]), b2 ? std::sqrt(se2[k] / count[k]) : 0.0});
  top = top > 0 ? top * 1.1 : 1.0;
  Plot plot;
  plot.width = 740;
  const float left = 80, right = 700, upper = 40, bottom = 380;
  auto px = [&](double ecc, double v) { return glm::vec2(left + (right - left) * ecc / bins, bottom - (bottom - upper) * v / top); };
  plot.strokes.push_back({{px(0, top), px(0, 0), px(bins, 0)}, glm::vec3(0), 1.5f, false});
  const int step = bins <= 20 ? 2 : bins <= 50 ? 5 : 10;
  for (int d = 0; d <= bins; d += step) {
    plot.strokes.push_back({{px(d, 0), px(d, 0) + glm::vec2(0, 6)}, glm::vec3(0), 1, false});
    plot.labels.push_back({px(d, 0) + glm::vec2(0, 22), std::to_string(d), 13, true});
  }
  for (int t = 0; t <= 4; ++t) {
    const double v = top / 1.1 * t / 4;
    plot.strokes.push_back({{px(0, v), px(0, v) - glm::vec2(6, 0)}, glm::vec3(0), 1, false});
    plot.labels.push_back({px(0, v) - glm::vec2(72, -5), fmt::format("{:.4f}", v), 12, false});
  }
  Stroke err{{}, glm::vec3(0.85f, 0.3f, 0.1f), 2.5f, false}, floor{{}, glm::vec3(0.55f), 2, false};
  for (int k = 0; k < bins; ++k)
    if (count[k]) {
      err.points.push_back(px(k + 0.5, std::sqrt(se[k] / count[k])));
      if (b2) floor.points.push_back(px(k + 0.5, std::sqrt(se2[k] / count[k])));
    }
  plot.strokes.push_back(err);
  if (b2) plot.strokes.push_back(floor);
  plot.labels.push_back({glm::vec2((left + right) / 2, bottom + 48), "eccentricity from the gaze (degrees)", 15, true});
  plot.labels.push_back(
      {glm::vec2(left, 24),
       b2 ? "RMSE per 1-degree bin: image vs reference (orange), reference noise (grey)" : "RMSE per 1-degree bin: image vs reference", 13,
       false});
  save_plot(plot, path);
}

}  // namespace foveal

namespace foveal {

namespace {
nlohmann::json json_number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(v > 0 ? "inf" : "-inf"); }
nlohmann::json stats_json(const ErrorStats& s) {
  return {{"pixels", s.pixels},
          {"rmse", s.rmse},
          {"mse", s.mse},
          {"psnr_db", json_number(s.psnr)},
          {"ssim", std::isfinite(s.ssim) ? nlohmann::json(s.ssim) : nlohmann::json(nullptr)},
          {"ssim_pixels", s.ssim_pixels}};
}
}  // namespace

nlohmann::json comparison_json(const Comparison& c, const Display& display) {
  nlohmann::json j = {{"width", c.width},
                      {"height", c.height},
                      {"gaze_px", {c.gaze_px.x, c.gaze_px.y}},
                      {"display",
                       {{"width_cm", display.width_cm},
                        {"height_cm", display.height_cm},
                        {"distance_cm", display.distance_cm},
                        {"res_x", display.res_x},
                        {"res_y", display.res_y}}},
                      {"whole", stats_json(c.whole)}};
  j["acuity_weighted_rmse"] = c.weighted_rmse;
  if (c.whole_noise) {
    j["whole_noise"] = stats_json(*c.whole_noise);
    j["acuity_weighted_noise_rmse"] = c.weighted_noise_rmse;
    j["acuity_weighted_ratio"] = c.weighted_ratio();
  }
  j["bands"] = nlohmann::json::array();
  for (const BandResult& r : c.bands) {
    nlohmann::json band = {{"name", r.band.name}, {"error", stats_json(r.error)}};
    if (!r.band.foveal_region) band["deg"] = {r.band.lo_deg, json_number(r.band.hi_deg)};
    if (r.noise) {
      band["noise"] = stats_json(*r.noise);
      band["noise_ratio"] = json_number(r.noise_ratio);
      band["noise_ratio_se"] = r.ratio_se;
      band["within_noise"] = r.within_noise;
    }
    j["bands"].push_back(band);
  }
  return j;
}

}  // namespace foveal
