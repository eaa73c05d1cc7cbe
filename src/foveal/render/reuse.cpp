// foveal/render/reuse.cpp — see reuse.h.
#include "foveal/render/reuse.h"

#include "foveal/render/pixel.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace foveal {
namespace {

// Angle one pixel spans at the image centre, radians (footprint = distance × this).
float pixel_angle(float fov_deg, int height) { return 2.0f * std::tan(glm::radians(fov_deg) * 0.5f) / static_cast<float>(height); }

constexpr float kSameNormal = 0.9f;  // cos 25.8°: the filter pools only pixels whose normals are this close

}  // namespace

float history_normal_cos(float quality) {
  const double q = std::clamp(static_cast<double>(quality), 0.01, 1.0);
  return static_cast<float>(std::cos(glm::radians(std::min(25.8, 5.7 / q))));
}

double history_reach_px(float quality) {
  const double q = std::clamp(static_cast<double>(quality), 1.0 / (1.0 + kMaxDenoiseRadius), 1.0);
  return 0.1 + 0.8 * (1.0 / q - 1.0);
}

uint64_t AoHistory::reproject(const GBuffer& g, const FoveationMaps& maps, const AoReuseParams& reuse,
                              AoCounts& counts) const {
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  counts.open.assign(pixels, 0.0f);
  counts.cast.assign(pixels, 0.0f);
  counts.origin_sum.assign(pixels, glm::vec3(0.0f));
  if (empty()) return 0;
  const CameraRays previous(camera_, width_, height_);
  const float angle = pixel_angle(camera_.fov_deg, height_);
  std::atomic<uint64_t> kept{0};
  tbb::parallel_for(0, g.height, [&](int y) {
    uint64_t row_kept = 0;
    for (int x = 0; x < g.width; ++x) {
      const size_t i = static_cast<size_t>(y) * g.width + x;
      if (!g.hit(i)) continue;
      double px = 0, py = 0;
      float distance = 0;
      if (!previous.project(g.position[i], px, py, distance)) continue;
      if (!(px >= 0 && py >= 0 && px < width_ && py < height_)) continue;
      // The four previous pixels around the point, bilinearly weighted, those that saw the same
      // surface (close normals, the point on their plane): their mean origin is the point's
      // own to first order, where one nearest pixel's is up to 0.7 px off
      const float footprint = angle * distance;
      const float normal_cos = history_normal_cos(maps.quality[i]);
      const double fx = px - 0.5, fy = py - 0.5;
      const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
      const double ax = fx - x0, ay = fy - y0;
      double weight = 0, open = 0, cast = 0;
      glm::dvec3 origin_sum(0.0);
      for (int k = 0; k < 4; ++k) {
        const int u = x0 + (k & 1), v = y0 + (k >> 1);
        if (u < 0 || v < 0 || u >= width_ || v >= height_) continue;
        const size_t j = static_cast<size_t>(v) * width_ + u;
        if (!hit_[j] || !(cast_[j] > 0)) continue;
        if (glm::dot(g.geo_normal[i], normal_[j]) < normal_cos) continue;
        if (std::fabs(glm::dot(g.position[i] - position_[j], normal_[j])) > 2.0f * footprint) continue;
        const double b = ((k & 1) ? ax : 1.0 - ax) * ((k >> 1) ? ay : 1.0 - ay);
        if (!(b > 0)) continue;
        weight += b;
        open += b * open_[j];
        cast += b * cast_[j];
        origin_sum += b * glm::dvec3(origin_[j]);
      }
      if (!(weight > 0)) continue;
      open /= weight;
      cast /= weight;
      origin_sum /= weight;
      // Where the history's rays were cast from: their mean origin, which drifts from the point
      // as the camera moves. To first order the estimate's bias is that offset times the
      // gradient of V, so the history is weighed down until the mean origin after this frame's
      // m = n/F rays at the point lies within the reach the eye allows: 0.1 px where q = 1,
      // growing as the cells it resolves (1/q px) grow.
      const glm::vec3 origin = glm::vec3(origin_sum / cast);
      const double d = glm::length(g.position[i] - origin) / std::max(footprint, 1e-12f);
      const double reach = history_reach_px(maps.quality[i]);
      float scale = 1.0f;
      if (d > reach) {
        const double m = refresh_rays(maps.rays[i], reuse.temporal_frames);
        scale = static_cast<float>(std::min(1.0, m * reach / ((d - reach) * cast)));
        if (!(scale * cast >= 1.0)) continue;  // less than a ray: none
      }
      counts.open[i] = static_cast<float>(scale * open);
      counts.cast[i] = static_cast<float>(scale * cast);
      counts.origin_sum[i] = glm::vec3(static_cast<double>(scale) * origin_sum);
      ++row_kept;
    }
    kept += row_kept;
  });
  return kept;
}

float history_cap_rays(int rays, float quality, const AoReuseParams& reuse) {
  const int f = std::max(1, reuse.temporal_frames);
  const int frames = std::max(f, static_cast<int>(std::lround(reuse.history_frames * std::clamp(quality, 0.0f, 1.0f))));
  return static_cast<float>(frames) * static_cast<float>(refresh_rays(rays, f));
}

void AoHistory::store(const GBuffer& g, const Camera& camera, const FoveationMaps& maps, const AoReuseParams& reuse,
                      const AoCounts& counts) {
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
    const float cap = history_cap_rays(maps.rays[i], maps.quality[i], reuse);
    const float cast = counts.cast[i];
    const float scale = cast > cap ? cap / cast : 1.0f;
    open_[i] = counts.open[i] * scale;
    cast_[i] = cast * scale;
    origin_[i] = counts.origin_sum.size() == pixels ? counts.origin_sum[i] * scale : cast * scale * g.position[i];
  });
  ++frames_;
}

int denoise_max_radius(float quality, const AoReuseParams& reuse) {
  if (!(quality > 0)) return kMaxDenoiseRadius;
  // The eye resolves cells of 1/q pixels (q = f_c(E)/f_c(0), and at q = 1 every pixel): pooling
  // within radius·(1/q − 1) pixels of a cell's neighbours, none where q = 1
  const double r = std::round(reuse.denoise_radius * (1.0 / quality - 1.0));
  return static_cast<int>(std::clamp(r, 0.0, static_cast<double>(kMaxDenoiseRadius)));
}

uint64_t denoise_visibility(const GBuffer& g, const FoveationMaps& maps, const AoCounts& c, const AoReuseParams& reuse,
                            float fov_deg, std::vector<float>& visibility) {
  const float angle = pixel_angle(fov_deg, g.height);
  const float tau_fovea = reuse.tau_fovea();
  constexpr float kAlbedoSigma = 0.15f;
  // Range weight: neighbours whose estimate differs from the pixel's by more than k(E) of their
  // combined standard error are weighed down as another AO (SVGF's luminance edge-stopping,
  // normalised by the estimates' variance), k(E) = 1/√q(E) widening as acuity falls. Measured
  // (acuity-weighted error × the reference's noise; none / k = 1 / 1/√q / 1/q): gaze off the dragon,
  // its crevices at 5–20° (420×262 orbit, temporal+adaptive+denoise) 1.53 / 1.17 / 1.22 / 1.28;
  // one frame at γ 4, the centre gaze, 1.57 / 1.71 / 1.63 / 1.60; gaze on the dragon 1.01 in all.
  constexpr float kRangeSigma = 1.0f;
  std::vector<float> out = visibility;
  std::atomic<uint64_t> changed{0};
  tbb::parallel_for(0, g.height, [&](int y) {
    uint64_t row_changed = 0;
    for (int x = 0; x < g.width; ++x) {
      const size_t i = static_cast<size_t>(y) * g.width + x;
      const float cast = c.cast[i];
      if (!g.hit(i) || !(cast > 0)) continue;
      // Is the pixel noisier than its eccentricity allows?
      const float se = visibility_standard_error(c.open[i], cast), spread = se * se * cast;
      const float tau = maps.quality[i] > 0 ? tau_fovea / maps.quality[i] : INFINITY;
      if (se <= tau) continue;
      // Just wide enough to pool the rays it lacks: (2r+1)² pixels of about its own count
      const float lacking = spread / (tau * tau) / cast;
      const int widest = denoise_max_radius(maps.quality[i], reuse);
      if (widest == 0) continue;
      const int radius = std::clamp(static_cast<int>(std::ceil(0.5f * std::sqrt(lacking))), 1, widest);
      const float sigma2 = static_cast<float>(radius * radius);
      const glm::vec3 pi = g.position[i], ni = g.normal[i], ai = g.albedo[i];
      const float vi = c.open[i] / cast;
      const float range2 = kRangeSigma * kRangeSigma / maps.quality[i];  // k(E)² (q > 0: τ is finite here)
      const float footprint = angle * g.depth[i];
      float open_sum = 0, cast_sum = 0;
      for (int v = std::max(0, y - radius); v <= std::min(g.height - 1, y + radius); ++v)
        for (int u = std::max(0, x - radius); u <= std::min(g.width - 1, x + radius); ++u) {
          const size_t j = static_cast<size_t>(v) * g.width + u;
          if (!g.hit(j) || !(c.cast[j] > 0)) continue;
          // Hard edges: a crease (normals apart) or a depth step (off the pixel's plane)
          if (glm::dot(ni, g.normal[j]) < kSameNormal) continue;
          const float d2 = static_cast<float>((u - x) * (u - x) + (v - y) * (v - y));
          const float plane = std::fabs(glm::dot(g.position[j] - pi, ni));
          if (plane > 0.5f * footprint * std::max(1.0f, std::sqrt(d2))) continue;
          const glm::vec3 da = g.albedo[j] - ai;
          // Range: estimates further apart than their noise explains are another AO (a crevice)
          const float vj = c.open[j] / c.cast[j], sej = visibility_standard_error(c.open[j], c.cast[j]);
          const float dv = vj - vi, var = range2 * (se * se + sej * sej);
          const float w = std::exp(-0.5f * d2 / sigma2 - 0.5f * glm::dot(da, da) / (kAlbedoSigma * kAlbedoSigma) - 0.5f * dv * dv / var);
          open_sum += w * c.open[j];
          cast_sum += w * c.cast[j];
        }
      const float v = cast_sum > 0 ? open_sum / cast_sum : visibility[i];
      if (v != visibility[i]) {
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
