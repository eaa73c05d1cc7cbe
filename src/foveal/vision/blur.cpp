// foveal/vision/blur.cpp — the gather blur, parallel over rows.
#include "foveal/vision/blur.h"

#include "foveal/util/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace foveal {

TapPattern make_tap_pattern(int taps) {
  if (taps < 1 || taps > 4096) fail("--blur-taps: must be in [1, 4096], got {}", taps);
  TapPattern t;
  t.offset.push_back({0, 0});
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < taps; ++k) {
    const double r = std::sqrt((k + 0.5) / taps), a = k * golden;
    t.offset.push_back(glm::vec2(r * std::cos(a), r * std::sin(a)));
  }
  // Each spiral point stands for an equal area of the disc; the centre for a tiny one
  for (size_t i = 0; i < t.offset.size(); ++i) {
    const float r2 = glm::dot(t.offset[i], t.offset[i]);
    t.weight.push_back(std::exp(-4.5f * r2) * (i == 0 ? 1.0f / taps : 1.0f));
  }
  return t;
}

int taps_for_diameter(float d, int max_taps) {
  if (!(d >= 0.25f)) return 0;
  // About one tap per pixel inside 2σ = d/3 of the centre, where the Gaussian's weight lies
  const int area = static_cast<int>(std::ceil(0.35f * d * d));
  return std::clamp(area, std::min(8, max_taps), max_taps);
}

namespace {

// Half-resolution copies (2×2 box), so that a large CoC's taps, spaced several pixels apart,
// read pre-averaged pixels instead of aliasing.
std::vector<Image> pyramid(const Image& img, int levels) {
  std::vector<Image> out{img};
  for (int l = 1; l < levels; ++l) {
    const Image& src = out.back();
    if (src.width < 4 || src.height < 4) break;
    Image dst((src.width + 1) / 2, (src.height + 1) / 2, src.channels);
    for (int y = 0; y < dst.height; ++y)
      for (int x = 0; x < dst.width; ++x) {
        const int x0 = 2 * x, y0 = 2 * y, x1 = std::min(x0 + 1, src.width - 1), y1 = std::min(y0 + 1, src.height - 1);
        for (int c = 0; c < src.channels; ++c)
          dst.at(x, y, c) = 0.25f * (src.at(x0, y0, c) + src.at(x1, y0, c) + src.at(x0, y1, c) + src.at(x1, y1, c));
      }
    out.push_back(std::move(dst));
  }
  return out;
}

}  // namespace

Image variable_blur(const Image& img, const std::vector<float>& coc, const BlurParams& params, const CocShape* shape) {
  if (coc.size() != size_t(img.width) * img.height) fail("blur: {} CoC values for a {}x{} image", coc.size(), img.width, img.height);
  if (shape && shape->scale.size() != coc.size()) fail("blur: {} CoC shapes for {} pixels", shape->scale.size(), coc.size());
  // The ellipse's axes in image coordinates (y down)
  const float axis_rad = shape ? glm::radians(shape->axis_deg) : 0.0f;
  const glm::vec2 along(std::cos(axis_rad), -std::sin(axis_rad)), across(std::sin(axis_rad), std::cos(axis_rad));
  // One pattern per tap count in use: counts are rounded up to a power of two (8 … taps) and the
  // full count
  std::vector<int> counts;
  for (int c = std::min(8, params.taps); c < params.taps; c *= 2) counts.push_back(c);
  counts.push_back(params.taps);
  std::vector<TapPattern> patterns;
  for (int c : counts) patterns.push_back(make_tap_pattern(c));
  auto pattern_for = [&](int taps) -> const TapPattern& {
    for (size_t k = 0; k < counts.size(); ++k)
      if (counts[k] >= taps) return patterns[k];
    return patterns.back();
  };
  const int w = img.width, h = img.height, ch = img.channels;
  if (ch < 1 || ch > 4) fail("blur: images of 1 to 4 channels, got {}", ch);
  const std::vector<Image> levels = pyramid(img, 5);
  // Smallest (clamped) CoC of each 16×16 tile: where every CoC within a pixel's reach is at least
  // as large as its own, every tap reaches it and the scatter-aware test can be skipped
  constexpr int kTile = 16;
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  std::vector<float> tile_min(size_t(tiles_x) * tiles_y, INFINITY);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float c = coc[size_t(y) * w + x];
      float& m = tile_min[size_t(y / kTile) * tiles_x + x / kTile];
      m = std::min(m, std::isfinite(c) ? std::min(c, params.max_diameter_px) : params.max_diameter_px);
    }
  // Smallest (clamped) CoC of each pixel's 2×2 bilinear footprint (x, x+1) × (y, y+1)
  std::vector<float> min_quad(size_t(w) * h);
  auto clamped = [&](size_t i) { return std::isfinite(coc[i]) ? std::min(coc[i], params.max_diameter_px) : params.max_diameter_px; };
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < w; ++x) {
        const int x1 = std::min(x + 1, w - 1), y1 = std::min(y + 1, h - 1);
        min_quad[size_t(y) * w + x] = std::min(std::min(clamped(size_t(y) * w + x), clamped(size_t(y) * w + x1)),
                                               std::min(clamped(size_t(y1) * w + x), clamped(size_t(y1) * w + x1)));
      }
  });
  auto min_coc_around = [&](int x, int y, float r) {
    const int tx0 = std::max(0, int(x - r - 2) / kTile), tx1 = std::min(tiles_x - 1, int(x + r + 2) / kTile);
    const int ty0 = std::max(0, int(y - r - 2) / kTile), ty1 = std::min(tiles_y - 1, int(y + r + 2) / kTile);
    float m = INFINITY;
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) m = std::min(m, tile_min[size_t(ty) * tiles_x + tx]);
    return m;
  };
  Image out(w, h, ch);
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 4), [&](const tbb::blocked_range<int>& rows) {
    float sum[4] = {0, 0, 0, 0};
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const float d = std::min(std::isfinite(coc[i]) ? coc[i] : params.max_diameter_px, params.max_diameter_px);
        const int n = taps_for_diameter(d, params.taps);
        if (n == 0) {  // sharp (also NaN): the pixel as it is
          for (int c = 0; c < ch; ++c) out.pixels[i * ch + c] = img.pixels[i * ch + c];
          continue;
        }
        const TapPattern& taps = pattern_for(n);
        // Taps are about `spacing` pixels apart (within 2σ); read the level whose pixels are that large
        const float spacing = d / 3.0f * std::sqrt(3.14159f / float(taps.offset.size()));
        int level = 0;
        while (level + 1 < int(levels.size()) && spacing >= 2.0f * float(1 << level)) ++level;
        const Image& src = levels[level];
        const float scale = 1.0f / float(1 << level), radius = 0.5f * d * scale;
        const float cx = (x + 0.5f) * scale - 0.5f, cy = (y + 0.5f) * scale - 0.5f;
        const int sw = src.width, sh = src.height;
        for (int c = 0; c < ch; ++c) sum[c] = 0;
        float total = 0;
        // A texel contributes only if its own CoC reaches this pixel (scatter-aware): a sharp
        // point does not spread. At level 0 each bilinear texel is checked; coarser levels check
        // the full-resolution pixel nearest to the tap.
        const bool check = params.scatter_aware && 0.5f * min_coc_around(x, y, 0.5f * d) + 0.5f < 0.5f * d + 1.5f;
        auto reaches = [&](int px, int py) {
          if (!check) return true;
          const float r = coc[size_t(py) * w + px];
          const float reach = 0.5f * (std::isfinite(r) ? std::min(r, params.max_diameter_px) : params.max_diameter_px) + 0.5f;
          const float dx = float(px - x), dy = float(py - y);
          return reach * reach >= dx * dx + dy * dy;
        };
        const glm::vec2 sc = shape ? shape->scale[i] : glm::vec2(1.0f);
        for (size_t k = 0; k < taps.offset.size(); ++k) {
          // The tap's offset: the unit-disc point, stretched into the pixel's ellipse
          const glm::vec2 o = shape ? taps.offset[k].x * sc.x * along + taps.offset[k].y * sc.y * across : taps.offset[k];
          // Bilinear read at the tap, clamped to the image
          const float sx = std::clamp(cx + radius * o.x, 0.0f, float(sw - 1));
          const float sy = std::clamp(cy + radius * o.y, 0.0f, float(sh - 1));
          const int x0 = std::min(int(sx), std::max(sw - 2, 0)), y0 = std::min(int(sy), std::max(sh - 2, 0));
          const int x1 = std::min(x0 + 1, sw - 1), y1 = std::min(y0 + 1, sh - 1);
          const float fx = sx - x0, fy = sy - y0, wk = taps.weight[k];
          const float w00 = (1 - fx) * (1 - fy) * wk, w10 = fx * (1 - fy) * wk, w01 = (1 - fx) * fy * wk, w11 = fx * fy * wk;
          if (check) {
            if (level == 0) {
              // One read: the smallest CoC of the 2×2 texels; a tap any of whose texels does not
              // reach is left out whole (conservative, and no sharp texel leaks in bilinearly)
              const float r = min_quad[size_t(y0) * w + x0];
              const float dx = sx - float(x), dy = sy - float(y), reach = 0.5f * r + 0.5f;
              if (reach * reach < dx * dx + dy * dy) continue;
            } else if (!reaches(std::clamp(int(x + 0.5f * d * o.x + 0.5f), 0, w - 1),
                                std::clamp(int(y + 0.5f * d * o.y + 0.5f), 0, h - 1))) {
              continue;
            }
          }
          const float* p00 = &src.pixels[(size_t(y0) * sw + x0) * ch];
          const float* p10 = &src.pixels[(size_t(y0) * sw + x1) * ch];
          const float* p01 = &src.pixels[(size_t(y1) * sw + x0) * ch];
          const float* p11 = &src.pixels[(size_t(y1) * sw + x1) * ch];
          for (int c = 0; c < ch; ++c) sum[c] += w00 * p00[c] + w10 * p10[c] + w01 * p01[c] + w11 * p11[c];
          total += w00 + w10 + w01 + w11;
        }
        if (!(total > 0)) {  // nothing reached (cannot happen with the centre tap, kept for safety)
          for (int c = 0; c < ch; ++c) out.pixels[i * ch + c] = img.pixels[i * ch + c];
          continue;
        }
        for (int c = 0; c < ch; ++c) out.pixels[i * ch + c] = sum[c] / total;
      }
  });
  return out;
}

}  // namespace foveal
