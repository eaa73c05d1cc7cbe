// foveal/vision/blur.cpp — the gather blur, parallel over rows.
#include "foveal/vision/blur.h"

#include "foveal/util/error.h"
#include "foveal/vision/blur_kernel.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <type_traits>

namespace foveal {

TapTable make_tap_table(int max_taps) {
  TapTable t;
  t.first_count = std::min(8, max_taps);
  t.max_taps = max_taps;
  for (int n = t.first_count; n <= max_taps; ++n) {
    const TapPattern p = make_tap_pattern(n);
    t.start.push_back(static_cast<int>(t.offsets.size()));
    t.offsets.insert(t.offsets.end(), p.offset.begin(), p.offset.end());
    t.weights.insert(t.weights.end(), p.weight.begin(), p.weight.end());
  }
  return t;
}

void ellipse_axes(float axis_deg, glm::vec2* along, glm::vec2* across) {
  const float axis_rad = glm::radians(axis_deg);
  *along = glm::vec2(std::cos(axis_rad), -std::sin(axis_rad));
  *across = glm::vec2(std::sin(axis_rad), std::cos(axis_rad));
}

TapPattern make_tap_pattern(int taps) {
  if (taps < 1 || taps > 4096) fail("blur_taps: must be in [1, 4096], got {}", taps);
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

namespace {

// Texels of up to four channels, padded to four so that a bilinear read is four vector loads.
typedef float v4 __attribute__((vector_size(16)));

struct Level {
  int width = 0, height = 0;
  std::vector<v4> texels;
};

// The image (padded to four channels) and half-resolution copies (2×2 box), so that a large
// CoC's taps, spaced several texels apart, read pre-averaged pixels instead of aliasing.
std::vector<Level> pyramid(const Image& img, int levels) {
  std::vector<Level> out(1);
  out[0].width = img.width;
  out[0].height = img.height;
  out[0].texels.resize(size_t(img.width) * img.height);
  const int ch = img.channels;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, out[0].texels.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      v4 t = {0, 0, 0, 0};
      for (int c = 0; c < ch; ++c) t[c] = img.pixels[i * ch + c];
      out[0].texels[i] = t;
    }
  });
  for (int l = 1; l < levels; ++l) {
    const Level& src = out.back();
    Level dst;
    dst.width = src.width;
    dst.height = src.height;
    if (!blur::next_level(&dst.width, &dst.height)) break;
    dst.texels.resize(size_t(dst.width) * dst.height);
    tbb::parallel_for(tbb::blocked_range<int>(0, dst.height, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < dst.width; ++x)
          dst.texels[size_t(y) * dst.width + x] = blur::box_average(src.texels.data(), src.width, src.height, x, y);
    });
    out.push_back(std::move(dst));
  }
  return out;
}

// Rows [y0, y1) of the output. Built twice where the compiler can: for x86-64-v3 (AVX2 and fused
// multiply-adds; 20–25 % faster, measured with bench/foveal_microbench) and for the baseline,
// chosen at load time by the CPU. The two round differently in the last bits, so a CPU without
// AVX2 may give an image a few 1e-7 apart; on one machine the image never depends on threads.
template <int CH>
inline FOVEAL_INLINE void gather_rows_of(const blur::GatherView<v4>& g, const float* image, float* out, int y0, int y1) {
  const int w = g.width;
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < w; ++x) blur::gather_pixel<CH>(g, image, out + (size_t(y) * w + x) * CH, x, y);
}

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void gather_rows(const blur::GatherView<v4>& g, const float* image, float* out, int channels, int y0, int y1) {
  switch (channels) {
    case 1:
      gather_rows_of<1>(g, image, out, y0, y1);
      break;
    case 2:
      gather_rows_of<2>(g, image, out, y0, y1);
      break;
    case 3:
      gather_rows_of<3>(g, image, out, y0, y1);
      break;
    default:
      gather_rows_of<4>(g, image, out, y0, y1);
      break;
  }
}

}  // namespace

Image variable_blur(const Image& img, const std::vector<float>& coc, const BlurParams& params, const CocShape* shape) {
  if (coc.size() != size_t(img.width) * img.height) fail("blur: {} CoC values for a {}x{} image", coc.size(), img.width, img.height);
  if (shape && shape->scale.size() != coc.size()) fail("blur: {} CoC shapes for {} pixels", shape->scale.size(), coc.size());
  const int w = img.width, h = img.height, ch = img.channels;
  if (ch < 1 || ch > 4) fail("blur: images of 1 to 4 channels, got {}", ch);
  const TapTable taps = make_tap_table(params.taps);  // a pattern for every tap count in use (8 … taps)
  const std::vector<Level> levels = pyramid(img, blur::kMaxLevels);
  // The CoCs clamped once (NaN and infinity: the largest), then the smallest of each tile
  std::vector<float> clamped(coc.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, coc.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) clamped[i] = blur::clamp_coc(coc[i], params.max_diameter_px);
  });
  const int tiles_x = (w + blur::kTile - 1) / blur::kTile, tiles_y = (h + blur::kTile - 1) / blur::kTile;
  std::vector<float> tile_min(size_t(tiles_x) * tiles_y);
  tbb::parallel_for(0, tiles_y, [&](int ty) {
    for (int tx = 0; tx < tiles_x; ++tx) tile_min[size_t(ty) * tiles_x + tx] = blur::tile_minimum(clamped.data(), w, h, tx, ty);
  });
  // Smallest CoC under each texel of each level (a min pyramid), then under each texel's 2×2
  // bilinear footprint (x, x+1) × (y, y+1)
  std::vector<std::vector<float>> min_quad(levels.size());
  std::vector<float> below = clamped, above;
  for (size_t l = 0; l < levels.size(); ++l) {
    const int lw = levels[l].width, lh = levels[l].height;
    if (l > 0) {  // min over the 2×2 texels of the level below
      const int bw = levels[l - 1].width, bh = levels[l - 1].height;
      above.resize(size_t(lw) * lh);
      for (int y = 0; y < lh; ++y)
        for (int x = 0; x < lw; ++x)
          above[size_t(y) * lw + x] =
              blur::min_of_block(below.data(), bw, 2 * x, 2 * y, std::min(2 * x + 1, bw - 1), std::min(2 * y + 1, bh - 1));
      std::swap(below, above);
    }
    std::vector<float>& quad = min_quad[l];
    quad.resize(size_t(lw) * lh);
    tbb::parallel_for(tbb::blocked_range<int>(0, lh, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < lw; ++x)
          quad[size_t(y) * lw + x] = blur::min_of_block(below.data(), lw, x, y, std::min(x + 1, lw - 1), std::min(y + 1, lh - 1));
    });
  }
  blur::GatherView<v4> g;
  g.width = w;
  g.height = h;
  g.coc = clamped.data();
  g.shape = shape ? shape->scale.data() : nullptr;
  if (shape) ellipse_axes(shape->axis_deg, &g.along, &g.across);  // in image coordinates (y down)
  g.level_count = static_cast<int>(levels.size());
  for (size_t l = 0; l < levels.size(); ++l) g.levels[l] = {levels[l].width, levels[l].height, levels[l].texels.data(), min_quad[l].data()};
  g.offsets = taps.offsets.data();
  g.weights = taps.weights.data();
  g.pattern_start = taps.start.data();
  g.first_count = taps.first_count;
  g.max_taps = taps.max_taps;
  g.scatter_aware = params.scatter_aware;
  g.tile_min = tile_min.data();
  g.tiles_x = tiles_x;
  g.tiles_y = tiles_y;
  Image out(w, h, ch);
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 4), [&](const tbb::blocked_range<int>& rows) {
    gather_rows(g, img.pixels.data(), out.pixels.data(), ch, rows.begin(), rows.end());
  });
  return out;
}

}  // namespace foveal
