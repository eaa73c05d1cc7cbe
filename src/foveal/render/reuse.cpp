// foveal/render/reuse.cpp — see reuse.h.
#include "foveal/render/reuse.h"

#include "foveal/render/pixel.h"
#include "foveal/util/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace foveal {
uint64_t AoHistory::reproject(const GBuffer& g, const FoveationMaps& maps, const AoReuseParams& reuse, AoCounts& counts) const {
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  counts.open.assign(pixels, 0.0f);
  counts.cast.assign(pixels, 0.0f);
  counts.origin_sum.assign(pixels, glm::vec3(0.0f));
  return reproject_rows(g, maps, reuse, counts, 0, g.height);
}

uint64_t AoHistory::reproject_rows(const GBuffer& g, const FoveationMaps& maps, const AoReuseParams& reuse, AoCounts& counts, int y0,
                                   int y1) const {
  const size_t end = static_cast<size_t>(y1) * static_cast<size_t>(g.width);
  if (y0 < 0 || y1 > g.height || y0 > y1 || counts.open.size() < end || counts.cast.size() < end || counts.origin_sum.size() < end ||
      maps.quality.size() < end || maps.rays.size() < end)
    fail("AoHistory::reproject_rows: rows [{}, {}) of a {}x{} view are not all held by the counts and maps", y0, y1, g.width, g.height);
  if (empty()) return 0;
  const HistoryView h = view();
  const SurfaceView surfaces = surface_view(g);
  const CountsView out = counts_view(counts);
  std::atomic<uint64_t> kept{0};
  tbb::parallel_for(y0, y1, [&](int y) {
    uint64_t row_kept = 0;
    for (int x = 0; x < g.width; ++x) {
      const size_t i = static_cast<size_t>(y) * g.width + x;
      if (g.hit(i) && reproject_pixel(h, surfaces, i, maps.quality[i], maps.rays[i], reuse.temporal_frames, out)) ++row_kept;
    }
    kept += row_kept;
  });
  return kept;
}

HistoryView AoHistory::view() const {
  HistoryView h = history_view(camera_, width_, height_);
  h.position = position_.data();
  h.normal = normal_.data();
  h.hit = hit_.data();
  h.open = open_.data();
  h.cast = cast_.data();
  h.origin = origin_.data();
  return h;
}

void AoHistory::store(const GBuffer& g, const Camera& camera, const FoveationMaps& maps, const AoReuseParams& reuse,
                      const AoCounts& counts) {
  rows_width_ = rows_height_ = rows_ = 0;  // (a store by rows under way is abandoned)
  width_ = g.width;
  height_ = g.height;
  camera_ = camera;
  position_ = g.position;
  normal_ = g.geo_normal;
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  hit_.resize(pixels);
  open_.resize(pixels);
  cast_.resize(pixels);
  origin_.resize(pixels);
  tbb::parallel_for(size_t(0), pixels, [&](size_t i) {
    hit_[i] = g.hit(i) ? 1 : 0;
    history_of_pixel(history_cap_rays(maps.rays[i], maps.quality[i], reuse), counts.open[i], counts.cast[i],
                     counts.origin_sum.size() == pixels ? counts.origin_sum.data() : nullptr, i, g.position[i], open_[i], cast_[i],
                     origin_[i]);
  });
  ++frames_;
}

void AoHistory::store(GBuffer&& g, const Camera& camera, const FoveationMaps& maps, const AoReuseParams& reuse, const PixelCounts& counts) {
  rows_width_ = rows_height_ = rows_ = 0;
  width_ = g.width;
  height_ = g.height;
  camera_ = camera;
  position_ = std::move(g.position);
  normal_ = std::move(g.geo_normal);
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  hit_.resize(pixels);
  open_.resize(pixels);
  cast_.resize(pixels);
  origin_.resize(pixels);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) keep_pixel(i, g.hit(i), maps, reuse, counts);
  });
  ++frames_;
}

void AoHistory::keep_pixel(size_t i, bool hit, const FoveationMaps& maps, const AoReuseParams& reuse, const PixelCounts& counts) {
  hit_[i] = hit ? 1 : 0;
  float open = 0, cast = 0;
  glm::vec3 origin_sum(0.0f);
  counts(i, position_[i], open, cast, origin_sum);
  history_of_pixel(history_cap_rays(maps.rays[i], maps.quality[i], reuse), open, cast, &origin_sum, 0, position_[i], open_[i], cast_[i],
                   origin_[i]);
}

void AoHistory::begin_rows(int width, int height, const Camera& camera) {
  if (width <= 0 || height <= 0) fail("AoHistory::begin_rows: a {}x{} view", width, height);
  width_ = height_ = 0;  // (empty until the last row is stored)
  rows_width_ = width;
  rows_height_ = height;
  rows_ = 0;
  camera_ = camera;
  const size_t pixels = static_cast<size_t>(width) * static_cast<size_t>(height);
  position_.clear();
  normal_.clear();
  hit_.clear();
  open_.clear();
  cast_.clear();
  origin_.clear();
  position_.reserve(pixels);
  normal_.reserve(pixels);
  hit_.reserve(pixels);
  open_.reserve(pixels);
  cast_.reserve(pixels);
  origin_.reserve(pixels);
}

void AoHistory::store_rows(const GBuffer& g, const FoveationMaps& maps, const AoReuseParams& reuse, const PixelCounts& counts, int y0,
                           int y1) {
  if (g.width != rows_width_ || g.height != rows_height_ || y0 != rows_ || y1 < y0 || y1 > rows_height_)
    fail("AoHistory::store_rows: rows [{}, {}) of a {}x{} view, where {} rows of a {}x{} one are stored", y0, y1, g.width, g.height, rows_,
         rows_width_, rows_height_);
  const size_t w = static_cast<size_t>(g.width), b = static_cast<size_t>(y0) * w, e = static_cast<size_t>(y1) * w;
  if (maps.rays.size() < e || maps.quality.size() < e || g.position.size() < e)
    fail("AoHistory::store_rows: rows [{}, {}) are not all held by the view and its maps", y0, y1);
  // (within the memory reserved: only these rows' pages are touched)
  position_.resize(e);
  normal_.resize(e);
  hit_.resize(e);
  open_.resize(e);
  cast_.resize(e);
  origin_.resize(e);
  tbb::parallel_for(tbb::blocked_range<size_t>(b, e, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      position_[i] = g.position[i];
      normal_[i] = g.geo_normal[i];
      keep_pixel(i, g.hit(i), maps, reuse, counts);
    }
  });
  rows_ = y1;
  if (rows_ == rows_height_) {
    width_ = rows_width_;
    height_ = rows_height_;
    ++frames_;
  }
}

uint64_t denoise_visibility(const GBuffer& g, const FoveationMaps& maps, const AoCounts& c, const AoReuseParams& reuse, float fov_deg,
                            std::vector<float>& visibility) {
  const float angle = pixel_angle(fov_deg, g.height);
  const float tau_fovea = reuse.tau_fovea();
  const SurfaceView surfaces = surface_view(g);
  std::vector<float> out = visibility;
  std::atomic<uint64_t> changed{0};
  tbb::parallel_for(0, g.height, [&](int y) {
    uint64_t row_changed = 0;
    for (int x = 0; x < g.width; ++x) {
      const size_t i = static_cast<size_t>(y) * g.width + x;
      float v = 0;
      if (denoise_pixel(surfaces, maps.quality.data(), c.open.data(), c.cast.data(), x, y, angle, tau_fovea, reuse.denoise_radius, v) &&
          v != visibility[i]) {
        out[i] = v;
        ++row_changed;
      }
    }
    changed += row_changed;
  });
  visibility.swap(out);
  return changed;
}

}  // namespace foveal
