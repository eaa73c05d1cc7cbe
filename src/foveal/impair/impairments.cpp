// foveal/impair/impairments.cpp — ocular media, field loss, metamorphopsia, colour; their order.
#include "foveal/impair/impairments.h"

#include "foveal/perception/foveation.h"
#include "foveal/util/error.h"
#include "foveal/util/timer.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>

namespace foveal {

namespace {

constexpr double kSrPerDeg2 = (std::numbers::pi / 180.0) * (std::numbers::pi / 180.0);

cv::Mat as_mat(Image& image) { return cv::Mat(image.height, image.width, image.channels == 3 ? CV_32FC3 : CV_32FC1, image.pixels.data()); }

double age_factor(double age) { return 1.0 + std::pow(age / 62.5, 4.0); }

// splitmix64: a portable, seedable sequence (the same distortion on every platform)
uint64_t splitmix(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
double uniform(uint64_t& state) { return (splitmix(state) >> 11) * 0x1.0p-53; }

}  // namespace

double cie_glare_psf(double theta, double age, double p, double straylight) {
  return 10.0 / (theta * theta * theta) + straylight * (5.0 / (theta * theta) + 0.1 * p / theta) * age_factor(age) + 0.0025 * p;
}

double cie_glare_fraction(double t1, double t2, double age, double p, double straylight) {
  if (!(t2 > t1)) return 0.0;
  const double g = straylight * age_factor(age);
  return 2.0 * std::numbers::pi * kSrPerDeg2 *
         (10.0 * (1.0 / t1 - 1.0 / t2) + 5.0 * g * std::log(t2 / t1) + 0.1 * p * g * (t2 - t1) + 0.0025 * p * (t2 * t2 - t1 * t1) / 2.0);
}

double cataract_straylight_factor(double severity) { return std::pow(10.0, std::clamp(severity, 0.0, 1.0)); }

glm::dvec3 lens_transmittance(const MediaParams& m) {
  // Pokorny, Smith & Lutze 1987: the multiplier of the age-dependent density D1
  auto multiplier = [](double age) { return age <= 60 ? 1.0 + 0.02 * (std::max(age, 20.0) - 32.0) : 1.56 + 0.0667 * (age - 60.0); };
  const glm::dvec3 d1(0.02, 0.05, 0.25);
  const double extra = multiplier(m.age_years) - multiplier(25.0) + 0.0667 * 20.0 * std::clamp(m.cataract, 0.0, 1.0);
  return glm::dvec3(std::pow(10.0, -d1.x * extra), std::pow(10.0, -d1.y * extra), std::pow(10.0, -d1.z * extra));
}

std::vector<float> glare_kernel(double ppd, int rx, int ry, const MediaParams& m) {
  const int w = 2 * rx + 1, h = 2 * ry + 1;
  std::vector<float> k(size_t(w) * h, 0.0f);
  const double s = cataract_straylight_factor(m.cataract);
  const double pixel_deg = 1.0 / ppd, pixel_sr = pixel_deg * pixel_deg * kSrPerDeg2;
  tbb::parallel_for(0, h, [&](int j) {
    for (int i = 0; i < w; ++i) {
      const int dx = i - rx, dy = j - ry;
      double v = 0;
      if (dx == 0 && dy == 0) {
        // the pixel itself: the scatter from 0.1° to the radius of a disc of the pixel's area
        v = cie_glare_fraction(kGlareMinDeg, pixel_deg / std::sqrt(std::numbers::pi), m.age_years, m.pigmentation, s);
      } else if (std::abs(dx) <= 2 && std::abs(dy) <= 2) {
        // near the centre the equation changes across a pixel: 8 × 8 sub-samples
        constexpr int n = 8;
        for (int b = 0; b < n; ++b)
          for (int a = 0; a < n; ++a) {
            const double t = std::hypot(dx + (a + 0.5) / n - 0.5, dy + (b + 0.5) / n - 0.5) * pixel_deg;
            if (t >= kGlareMinDeg) v += cie_glare_psf(t, m.age_years, m.pigmentation, s) * pixel_sr / (n * n);
          }
      } else {
        v = cie_glare_psf(std::hypot(dx, dy) * pixel_deg, m.age_years, m.pigmentation, s) * pixel_sr;
      }
      k[size_t(j) * w + i] = static_cast<float>(v);
    }
  });
  return k;
}

struct GlareSpectrum {
  int width = 0, height = 0;  // the reduced grid
  double ppd = 0;
  MediaParams media;
  cv::Size padded;
  cv::Mat spectrum;  // the kernel's DFT (CCS packed)
  double eta = 0;    // the kernel's sum
};

GlareGrid glare_grid(int width, int height) {
  // the scatter is smooth beyond a few tenths of a degree: compute it on a grid of at most 160 columns
  const int factor = std::max(1, (width + 159) / 160);
  return {factor, (width + factor - 1) / factor, (height + factor - 1) / factor};
}

std::vector<float> glare_grid_kernel(const GlareGrid& grid, double grid_ppd, const MediaParams& m, double* eta_out) {
  // the kernel covers every pair of pixels
  std::vector<float> k = glare_kernel(grid_ppd, grid.columns - 1, grid.rows - 1, m);
  double eta = 0;
  for (float v : k) eta += v;
  if (eta > 0.95) {  // more than the light there is: the straylight saturates
    for (float& v : k) v = static_cast<float>(v * 0.95 / eta);
    eta = 0.95;
  }
  if (eta_out) *eta_out = eta;
  return k;
}

void apply_glare(Image& image, double ppd, const MediaParams& m, std::shared_ptr<GlareSpectrum>* cache) {
  if (image.empty()) return;
  const GlareGrid grid = glare_grid(image.width, image.height);
  const int factor = grid.factor;
  const cv::Mat full = as_mat(image);
  cv::Mat small;
  if (factor > 1)
    cv::resize(full, small, cv::Size(grid.columns, grid.rows), 0, 0, cv::INTER_AREA);
  else
    small = full.clone();
  const double small_ppd = ppd * small.cols / image.width;
  std::shared_ptr<GlareSpectrum> g = cache ? *cache : nullptr;
  if (!g || g->width != small.cols || g->height != small.rows || g->ppd != small_ppd || g->media.age_years != m.age_years ||
      g->media.pigmentation != m.pigmentation || g->media.cataract != m.cataract) {
    // the linear convolution fits the padded size
    g = std::make_shared<GlareSpectrum>();
    g->width = small.cols;
    g->height = small.rows;
    g->ppd = small_ppd;
    g->media = m;
    const int rx = small.cols - 1, ry = small.rows - 1;
    std::vector<float> k = glare_grid_kernel(grid, small_ppd, m, &g->eta);
    g->padded = cv::Size(cv::getOptimalDFTSize(small.cols + 2 * rx), cv::getOptimalDFTSize(small.rows + 2 * ry));
    cv::Mat padded = cv::Mat::zeros(g->padded, CV_32F);
    cv::Mat(2 * ry + 1, 2 * rx + 1, CV_32F, k.data()).copyTo(padded(cv::Rect(0, 0, 2 * rx + 1, 2 * ry + 1)));
    cv::dft(padded, g->spectrum, 0, 2 * ry + 1);
    if (cache) *cache = g;
  }
  std::vector<cv::Mat> channels;
  cv::split(small, channels);
  for (cv::Mat& c : channels) {
    cv::Mat padded = cv::Mat::zeros(g->padded, CV_32F), spectrum, product, conv;
    c.copyTo(padded(cv::Rect(0, 0, c.cols, c.rows)));
    cv::dft(padded, spectrum, 0, c.rows);
    cv::mulSpectrums(spectrum, g->spectrum, product, 0);
    cv::dft(product, conv, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
    // the kernel's centre sits at (cols − 1, rows − 1) of the full convolution
    conv(cv::Rect(c.cols - 1, c.rows - 1, c.cols, c.rows)).copyTo(c);
  }
  cv::Mat scattered;
  cv::merge(channels, scattered);
  thread_local cv::Mat up_buffer;  // full size, kept per thread
  cv::Mat& up = up_buffer;
  if (factor > 1)
    cv::resize(scattered, up, full.size(), 0, 0, cv::INTER_LINEAR);
  else
    scattered.copyTo(up);
  const float keep = static_cast<float>(1.0 - g->eta);
  const size_t n = image.pixels.size();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
    const float* u = up.ptr<float>();
    for (size_t i = r.begin(); i < r.end(); ++i) image.pixels[i] = keep * image.pixels[i] + u[i];
  });
}

void apply_glare(Image& image, double ppd, const MediaParams& m) { apply_glare(image, ppd, m, nullptr); }

FieldMode parse_field_mode(const std::string& name) {
  for (FieldMode m : {FieldMode::contrast, FieldMode::blur, FieldMode::grey, FieldMode::fill})
    if (name == to_string(m)) return m;
  fail("unknown field-loss mode '{}' (expected contrast, blur, grey or fill)", name);
}

const char* to_string(FieldMode mode) {
  switch (mode) {
    case FieldMode::contrast:
      return "contrast";
    case FieldMode::blur:
      return "blur";
    case FieldMode::grey:
      return "grey";
    case FieldMode::fill:
      return "fill";
  }
  return "?";
}

namespace {

// Multiply each channel of `a` (float, any channel count) by the one-channel `w`, in place.
void scale_channels(cv::Mat& a, const cv::Mat& w) {
  const int n = a.channels();
  tbb::parallel_for(tbb::blocked_range<int>(0, a.rows, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      float* p = a.ptr<float>(y);
      const float* s = w.ptr<float>(y);
      for (int x = 0; x < a.cols; ++x)
        for (int c = 0; c < n; ++c) p[x * n + c] *= s[x];
    }
  });
}

}  // namespace

int field_pyramid_levels(int width, int height) {
  int levels = 0;
  while (levels < 8 && std::min(width, height) >= 16) {
    width = (width + 1) / 2;
    height = (height + 1) / 2;
    ++levels;
  }
  return levels;
}

void apply_field_loss(Image& image, const std::vector<float>& loss_db, FieldMode mode) {
  if (loss_db.size() != size_t(image.width) * image.height)
    fail("field loss: {} values for a {}x{} image", loss_db.size(), image.width, image.height);
  cv::Mat img = as_mat(image);
  const cv::Mat loss(image.height, image.width, CV_32F, const_cast<float*>(loss_db.data()));
  if (image.channels != 3) fail("field loss needs a 3-channel image, got {} channels", image.channels);
  cv::Mat m;  // the remaining sensitivity 10^(−L/10), for grey and fill
  if (mode == FieldMode::grey || mode == FieldMode::fill) {
    const cv::Mat scaled_loss = loss * (-std::log(10.0) / 10.0);
    cv::exp(scaled_loss, m);
  }
  if (mode == FieldMode::grey) {
    const cv::Scalar mean = cv::mean(img);
    cv::Mat fill(img.size(), img.type(), mean), keep = img.clone(), rest = 1.0 - m;
    scale_channels(keep, m);
    scale_channels(fill, rest);
    cv::Mat out = keep + fill;
    out.copyTo(img);
    return;
  }
  const int levels = field_pyramid_levels(img.cols, img.rows);
  std::vector<cv::Mat> g{img};  // level 0 is the image itself (read before the last pass writes it)
  for (int k = 0; k < levels; ++k) {
    cv::Mat down;
    cv::pyrDown(g.back(), down);
    g.push_back(down);
  }
  if (mode == FieldMode::fill) {
    // push: premultiplied colour and weight down the pyramid; pull: each level keeps what it sees
    // and takes the rest from the level below
    std::vector<cv::Mat> pc{img.clone()}, pw{m.clone()};
    scale_channels(pc[0], m);
    for (int k = 0; k < levels; ++k) {
      cv::Mat c, w;
      cv::pyrDown(pc.back(), c);
      cv::pyrDown(pw.back(), w);
      pc.push_back(c);
      pw.push_back(w);
    }
    cv::Mat fill = pc.back().clone();
    const cv::Mat floor_w = cv::max(pw.back(), 1e-6);
    const cv::Mat inv = 1.0 / floor_w;
    scale_channels(fill, inv);
    for (int k = levels - 1; k >= 0; --k) {
      cv::Mat up;
      cv::pyrUp(fill, up, pc[k].size());
      const cv::Mat missing = 1.0 - pw[k];
      const cv::Mat rest = cv::max(missing, 0.0);
      scale_channels(up, rest);
      fill = pc[k] + up;
    }
    fill.copyTo(img);
    return;
  }
  // Laplacian bands, each scaled by its weight at its own resolution; the finest level is fused
  // into one pass that writes the image (full-size buffers kept per thread: no page faults per frame)
  const float ln10_10 = static_cast<float>(std::log(10.0) / 10.0);
  auto weight = [&](float l, int k) {
    return mode == FieldMode::contrast ? std::exp(-l * ln10_10) : std::clamp((k + 1.0f) - l / 6.0f, 0.0f, 1.0f);
  };
  cv::Mat out = g[levels].clone();
  thread_local cv::Mat up_g_buffer, up_o_buffer;
  cv::Mat& up_g = up_g_buffer;  // (the workers below see this thread's buffers through these)
  cv::Mat& up_o = up_o_buffer;
  for (int k = levels - 1; k >= 0; --k) {
    const cv::Mat& gk = k == 0 ? img : g[k];
    cv::pyrUp(g[k + 1], up_g, gk.size());
    cv::pyrUp(out, up_o, gk.size());
    cv::Mat lk;
    if (k == 0)
      lk = loss;
    else
      cv::resize(loss, lk, gk.size(), 0, 0, cv::INTER_LINEAR);
    cv::Mat& dst = k == 0 ? img : up_o;  // the finest level writes the image itself
    tbb::parallel_for(tbb::blocked_range<int>(0, gk.rows, 8), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y) {
        const float* gp = gk.ptr<float>(y);
        const float* ug = up_g.ptr<float>(y);
        const float* uo = up_o.ptr<float>(y);
        const float* lp = lk.ptr<float>(y);
        float* d = dst.ptr<float>(y);
        for (int x = 0; x < gk.cols; ++x) {
          const float w = lp[x] == 0.0f ? 1.0f : weight(lp[x], k);
          for (int c = 0; c < 3; ++c) d[x * 3 + c] = uo[x * 3 + c] + w * (gp[x * 3 + c] - ug[x * 3 + c]);
        }
      }
    });
    if (k > 0) out = up_o.clone();
  }
}

MetamorphopsiaBumps Metamorphopsia::bumps() const {
  MetamorphopsiaBumps b;
  b.radius = radius_deg;
  b.sigma = radius_deg / 3.0;
  b.half_amplitude = any() ? amplitude_deg / 2.0 : 0.0;
  // 12 Gaussian bumps in the disc, each pushing in its own direction
  uint64_t state = seed * 0x2545F4914F6CDD1Dull + 17;
  for (int k = 0; k < MetamorphopsiaBumps::kCount; ++k) {
    const double cr = radius_deg * std::sqrt(uniform(state)), ca = 2 * std::numbers::pi * uniform(state);
    const double da = 2 * std::numbers::pi * uniform(state);
    b.cx[k] = cr * std::cos(ca);
    b.cy[k] = cr * std::sin(ca);
    b.ux[k] = std::cos(da);
    b.uy[k] = std::sin(da);
  }
  return b;
}

Retinotopy expand(const RetinotopyGrid& g) {
  Retinotopy r{g.width, g.height, std::vector<glm::vec2>(g.field_deg.empty() ? 0 : size_t(g.width) * g.height), g.ppd};
  if (g.field_deg.empty()) return r;
  tbb::parallel_for(tbb::blocked_range<int>(0, g.height, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < g.width; ++x) r.field_deg[size_t(y) * g.width + x] = retinotopy_between(g.field_deg.data(), g.columns, x, y);
  });
  return r;
}

std::string Impairments::describe() const {
  std::string s;
  auto add = [&](const std::string& part) { s += (s.empty() ? "" : ", ") + part; };
  if (media.glare) add(fmt::format("glare (age {}, cataract {})", media.age_years, media.cataract));
  if (media.yellowing) add("lens yellowing");
  if (!field.empty()) add(fmt::format("field loss ({}, {})", field.view, to_string(field_mode)));
  if (metamorphopsia.any()) add(fmt::format("metamorphopsia {}° within {}°", metamorphopsia.amplitude_deg, metamorphopsia.radius_deg));
  if (cvd.type != CvdType::none) add(fmt::format("{} {}", to_string(cvd.type), cvd.severity));
  return s.empty() ? "none" : s;
}

ImpairmentPasses::ImpairmentPasses(const Impairments& impairments) : impairments_(impairments), map_(impairments.field.map()) {
  static std::atomic<uint64_t> next{1};
  id_ = next++;
}

std::vector<float> ImpairmentPasses::loss_db(const Retinotopy& r) const {
  std::vector<float> loss(r.field_deg.size(), 0.0f);
  if (map_.empty()) return loss;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, loss.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) loss[i] = static_cast<float>(map_.loss_db(r.field_deg[i].x, r.field_deg[i].y));
  });
  return loss;
}

ImpairTimes ImpairmentPasses::apply(Image& image, const Retinotopy& r) const {
  const Timer total;
  ImpairTimes t;
  const Impairments& im = impairments_;
  if (image.channels != 3) fail("impairments need a 3-channel image, got {}", image.channels);
  if (needs_retinotopy() && size_t(image.width) * image.height != r.field_deg.size())
    fail("impairments: the retinotopy does not fit the image");
  {  // 1. Ocular media
    const Timer timer;
    if (im.media.glare) apply_glare(image, r.ppd, im.media, &glare_cache_);
    if (im.media.yellowing) {
      const glm::dvec3 tr = lens_transmittance(im.media);
      const size_t n = size_t(image.width) * image.height;
      for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) image.pixels[i * 3 + c] *= static_cast<float>(tr[c]);
    }
    t.media_ms = timer.ms();
  }
  {  // 2. Retina: metamorphopsia moves the image, the field loss acts where it lands
    const Timer timer;
    if (im.metamorphopsia.any()) {
      // the distortion is smooth: displacements on a grid of every 4th pixel, interpolated
      constexpr int step = 4;
      const int gw = (image.width + step - 1) / step + 1, gh = (image.height + step - 1) / step + 1;
      cv::Mat gx(gh, gw, CV_32F), gy(gh, gw, CV_32F);
      const MetamorphopsiaBumps bumps = im.metamorphopsia.bumps();  // the seed's, drawn once (not per point)
      tbb::parallel_for(0, gh, [&](int j) {
        for (int i = 0; i < gw; ++i) {
          const int x = std::min(i * step, image.width - 1), y = std::min(j * step, image.height - 1);
          const glm::vec2 f = r.field_deg[size_t(y) * image.width + x];
          const glm::dvec2 d = metamorphopsia_displacement(bumps, f.x, f.y);
          gx.at<float>(j, i) = static_cast<float>(d.x * r.ppd);
          gy.at<float>(j, i) = static_cast<float>(-d.y * r.ppd);
        }
      });
      // only the rectangle where something moves is remapped (the distortion is zero beyond R + 1°)
      int i0 = gw, i1 = -1, j0 = gh, j1 = -1;
      for (int j = 0; j < gh; ++j)
        for (int i = 0; i < gw; ++i)
          if (gx.at<float>(j, i) != 0.0f || gy.at<float>(j, i) != 0.0f)
            i0 = std::min(i0, i), i1 = std::max(i1, i), j0 = std::min(j0, j), j1 = std::max(j1, j);
      if (i1 >= 0) {
        const int x0 = std::max(0, (i0 - 1) * step), y0 = std::max(0, (j0 - 1) * step);
        const cv::Rect roi(x0, y0, std::min(image.width, (i1 + 1) * step + 1) - x0, std::min(image.height, (j1 + 1) * step + 1) - y0);
        thread_local cv::Mat map_x_buffer, map_y_buffer, source_buffer;  // kept per thread
        cv::Mat& map_x = map_x_buffer;
        cv::Mat& map_y = map_y_buffer;
        map_x.create(roi.height, roi.width, CV_32F);
        map_y.create(roi.height, roi.width, CV_32F);
        tbb::parallel_for(0, roi.height, [&](int ry) {
          const int y = roi.y + ry, j = y / step;
          const float ty = float(y - j * step) / step;
          float* mx = map_x.ptr<float>(ry);
          float* my = map_y.ptr<float>(ry);
          for (int rx = 0; rx < roi.width; ++rx) {
            const int x = roi.x + rx, i = x / step;
            const float tx = float(x - i * step) / step;
            auto lerp2 = [&](const cv::Mat& m) {
              return (1 - ty) * ((1 - tx) * m.at<float>(j, i) + tx * m.at<float>(j, i + 1)) +
                     ty * ((1 - tx) * m.at<float>(j + 1, i) + tx * m.at<float>(j + 1, i + 1));
            };
            mx[rx] = static_cast<float>(x) + lerp2(gx);
            my[rx] = static_cast<float>(y) + lerp2(gy);
          }
        });
        cv::Mat& src = source_buffer;
        as_mat(image).copyTo(src);
        cv::Mat dst = as_mat(image)(roi);
        cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
      }
    }
    if (!map_.empty()) apply_field_loss(image, loss_db(r), im.field_mode);
    t.field_ms = timer.ms();
  }
  {  // 3. Colour vision
    const Timer timer;
    apply_cvd(im.cvd, image);
    t.colour_ms = timer.ms();
  }
  t.total_ms = total.ms();
  return t;
}

Retinotopy display_retinotopy(const Display& display, int width, int height, glm::dvec2 gaze_px) {
  FoveationParams round;
  round.ellipse_ratio = 1.0;
  const FoveationModel model(display, width, height, gaze_px, round);
  Retinotopy r{width, height, std::vector<glm::vec2>(size_t(width) * height), pixels_per_degree(display) * width / display.res_x};
  tbb::parallel_for(0, height, [&](int y) {
    for (int x = 0; x < width; ++x) {
      const FoveaSample s = model.evaluate(x, y);
      r.field_deg[size_t(y) * width + x] = glm::vec2(static_cast<float>(s.ex_deg), static_cast<float>(-s.ey_deg));
    }
  });
  return r;
}

Image amsler_grid(const ImpairmentPasses& passes, double ppd) {
  const int size = static_cast<int>(std::lround(22 * ppd));  // 20° of grid and a 1° margin
  Image grid(size, size, 3, 0.0f);
  const double c = size / 2.0;
  const float line = static_cast<float>(std::max(1.0, ppd / 12));
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double fx = (x + 0.5 - c) / ppd, fy = (y + 0.5 - c) / ppd;
      const bool inside = std::abs(fx) <= 10.0 + 0.5 / ppd && std::abs(fy) <= 10.0 + 0.5 / ppd;
      // pixels from the nearest line (lines every ppd pixels through the centre)
      const double gx = std::abs(std::remainder(x + 0.5 - c, ppd)), gy = std::abs(std::remainder(y + 0.5 - c, ppd));
      const bool on = inside && (gx <= line / 2 + 1e-9 || gy <= line / 2 + 1e-9);
      const bool dot = std::hypot(fx, fy) * ppd < 2.5 * line;
      if (on || dot) grid.at(x, y, 0) = grid.at(x, y, 1) = grid.at(x, y, 2) = 1.0f;
    }
  Retinotopy r{size, size, std::vector<glm::vec2>(size_t(size) * size), ppd};
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) r.field_deg[size_t(y) * size + x] = glm::vec2((x + 0.5 - c) / ppd, (c - y - 0.5) / ppd);
  passes.apply(grid, r);
  return grid;
}

}  // namespace foveal
