// foveal/render/reuse_pixel.h — quality per AO ray, pixel by pixel, written once for both backends.
//
// The adaptive rounds of a pixel's AO rays, the reprojection of its history, the history it
// leaves for the next frame and the edge-stopping filter are FOVEAL_HD functions over plain views
// of the buffers: render.cpp and reuse.cpp call them from oneTBB loops over std::vectors, the
// CUDA kernels (cuda/gpu_reuse.cu) from GPU threads over device arrays. What is decided here is
// the same on both; the two backends differ only where float arithmetic does (the G-buffer's
// last bits, which side of an edge a grazing ray lands on). The models are described in reuse.h.
#pragma once

#include "foveal/render/pixel.h"
#include "foveal/util/hd.h"
#include "foveal/util/sampling.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace foveal {

inline constexpr int kMaxDenoiseRadius = 8;

// The surface each pixel's primary ray found (host or device memory).
struct SurfaceView {
  const uint32_t* prim = nullptr;  // Hit::kNoHit where nothing was hit
  const glm::vec3* position = nullptr;
  const glm::vec3* normal = nullptr;      // shading normal
  const glm::vec3* geo_normal = nullptr;  // geometric normal (the AO hemisphere)
  const glm::vec3* albedo = nullptr;
  const float* depth = nullptr;
  int width = 0, height = 0;
  FOVEAL_HD bool hit(size_t i) const { return prim[i] != Hit::kNoHit; }
};

// A frame's AO ray counts per pixel (see AoCounts); origin_sum may be null (no history kept).
struct CountsView {
  float* open = nullptr;
  float* cast = nullptr;
  glm::vec3* origin_sum = nullptr;
};

// How the AO pass spends each pixel's budget (render.h's ao_sampling() makes it from
// AoReuseParams; the default is the paper's).
struct AoSampling {
  bool adaptive = false;
  int first_round = 16;      // adaptive: rays of the first round
  float tau_fovea = 0;       // adaptive: the standard error allowed where q = 1 (τ(E) = tau_fovea / q)
  int temporal_frames = 0;   // > 0: with history, m = ceil(n/F) rays a frame, or what n lacks
  uint32_t frame_index = 0;  // temporal: frames before this one; frame f > 0 starts the sequence
                             // of a pixel with history at (F + f − 1)·m, after frame 0's n = F·m
                             // rays (one without starts at 0, as the paper's pixel)
};

// m = ceil(n/F): the rays a pixel with n(E) = n casts a frame once its history holds n (F = temporal_frames).
FOVEAL_HD inline int refresh_rays(int n, int temporal_frames) {
  const int f = temporal_frames > 1 ? temporal_frames : 1;
  return (n + f - 1) / f;
}

// Standard error of a visibility estimate from `open` of `cast` rays: the binomial one at the
// Krichevsky–Trofimov estimate p = (open + ½)/(cast + 1), so that rays that all agree are not
// taken for an exact answer (with k rays all open it is about 0.71/k, not 0).
FOVEAL_HD inline float visibility_standard_error(float open, float cast) {
  if (!(cast > 0)) return 1.0f;
  const float p = (open + 0.5f) / (cast + 1.0f);
  return std::sqrt(p * (1.0f - p) / cast);
}

// Whether a pixel's fresh rays contradict its history: their visibilities differ by more than
// kHistoryContradiction standard errors of the difference (a two-proportion z-test; the pooled
// proportion Krichevsky–Trofimov smoothed). The pass then drops the history.
inline constexpr float kHistoryContradiction = 3.0f;
FOVEAL_HD inline bool history_contradicted(float history_open, float history_cast, float open, float cast) {
  if (!(history_cast > 0) || !(cast > 0)) return false;
  const float p = (history_open + open + 0.5f) / (history_cast + cast + 1.0f);
  const float se = std::sqrt(p * (1.0f - p) * (1.0f / history_cast + 1.0f / cast));
  return std::fabs(open / cast - history_open / history_cast) > kHistoryContradiction * se;
}

// ---- The AO pass: one pixel's rounds --------------------------------------------------------

// Where a pixel's rays come from this frame and how many it may cast.
struct AoPixelPlan {
  uint32_t limit = 0;   // rays at most this frame
  uint32_t offset = 0;  // index of its first ray in its sequence
  uint32_t first = 0;   // the first round's end
  uint64_t seed = 0;    // the sequence's scramble
};

// The AO seed of a sequence scrambled for frame (or view) `index` ≥ 1: a pixel that carries rays on
// from earlier frames casts the start of this sequence instead of a later stretch of its own.
FOVEAL_HD inline uint64_t scrambled_seed(uint64_t seed, uint32_t index) {
  return seed ^ (static_cast<uint64_t>(hash32(0x7e4b0000U + index)) << 32);
}

// A pixel with n(E) = n rays and `history_cast` rays of history.
FOVEAL_HD inline AoPixelPlan plan_ao_pixel(int n, float history_cast, const AoSampling& s, uint64_t seed) {
  int limit = n;
  AoPixelPlan plan;
  plan.seed = seed;
  if (s.temporal_frames > 0) {
    // What n lacks after the history, but at least m = n/F (history refreshes over F frames).
    // A still pixel's rays continue its sequence: frame 0 casts rays [0, F·m), frame f the
    // next m, so that its history is a prefix of the sequence, stratified as the paper's n.
    const int refresh = refresh_rays(n, s.temporal_frames);
    const int lack = static_cast<int>(std::ceil(static_cast<float>(n) - history_cast));
    limit = std::max(refresh, std::min(n, lack));
    // A pixel without history (a disocclusion, the first frame) casts the paper's first n
    // rays. One whose history falls short of n (weighed down, or adaptive stopped early)
    // casts the start of a sequence scrambled for this frame: a later stretch of its own
    // sequence is less evenly spread than any sequence's start (measured: ~1.3× the
    // reference's noise in the fovea of a moving camera).
    if (s.frame_index > 0 && history_cast > 0) {
      if (limit > refresh)
        plan.seed = scrambled_seed(seed, s.frame_index);
      else
        plan.offset = (static_cast<uint32_t>(s.temporal_frames) + s.frame_index - 1) * static_cast<uint32_t>(refresh);
    }
  }
  plan.limit = static_cast<uint32_t>(limit);
  plan.first = static_cast<uint32_t>(s.adaptive ? std::min(s.first_round, limit) : limit);
  return plan;
}

// One pixel's rays in rounds: cast rays [offset + cast, offset + round_end) of its sequence,
// count the blocked ones, then next_round() judges the pixel on all its rays.
struct AoPixelRounds {
  uint32_t cast = 0, round_end = 0, limit = 0;
  uint32_t blocked = 0;
  uint32_t offset = 0;   // index of the first ray in the pixel's sequence this frame
  uint32_t n = 0;        // the pixel's n(E)
  uint32_t dropped = 0;  // rays cast this frame before its history was dropped

  AoPixelRounds() = default;
  FOVEAL_HD AoPixelRounds(const AoPixelPlan& plan, int rays)
      : round_end(plan.first), limit(plan.limit), offset(plan.offset), n(static_cast<uint32_t>(rays)) {}

  // After a round, pixel i of `c` (its history): true when it casts another round (round_end moved on).
  FOVEAL_HD bool next_round(const CountsView& c, size_t i, float quality, const AoSampling& s) {
    // History this frame's rays contradict (an occluder that moved, another surface) is dropped,
    // with them: the pixel starts again without history, n(E) rays from its sequence's start
    if (s.temporal_frames > 0 && history_contradicted(c.open[i], c.cast[i], static_cast<float>(cast - blocked), static_cast<float>(cast))) {
      c.open[i] = c.cast[i] = 0.0f;
      if (c.origin_sum) c.origin_sum[i] = glm::vec3(0.0f);
      dropped += cast;
      cast = blocked = offset = 0;
      limit = n;
      round_end = s.adaptive ? std::min(static_cast<uint32_t>(s.first_round), n) : n;
      return true;
    }
    if (cast >= limit) return false;
    if (s.adaptive) {
      const float all_cast = c.cast[i] + static_cast<float>(cast);
      const float all_open = c.open[i] + static_cast<float>(cast - blocked);
      if (visibility_standard_error(all_open, all_cast) * quality <= s.tau_fovea) return false;
    }
    round_end = std::min(limit, 2 * cast);
    return true;
  }

  // Adds the frame's rays to pixel i of `c` (their origin: the pixel's surface point); returns
  // the rays traced this frame (16 bits).
  FOVEAL_HD uint16_t finish(const CountsView& c, size_t i, glm::vec3 position) const {
    c.open[i] += static_cast<float>(cast - blocked);
    c.cast[i] += static_cast<float>(cast);
    if (c.origin_sum) c.origin_sum[i] += static_cast<float>(cast) * position;
    const uint32_t traced = dropped + cast;
    return static_cast<uint16_t>(traced < 65535U ? traced : 65535U);
  }
};

// ---- Temporal history ------------------------------------------------------------------------

// Angle one pixel spans at the image centre, radians (footprint = distance × this).
FOVEAL_HD inline float pixel_angle(float fov_deg, int height) {
  return 2.0f * std::tan(glm::radians(fov_deg) * 0.5f) / static_cast<float>(height);
}

// The cosine of the widest angle between the geometric normal a pixel's history was cast about
// and its own: 5.7° where q = 1 (a facet tilted more biases AO beyond the reference's noise,
// measured on the dragon), 5.7°/q up to 25.8° as acuity falls.
FOVEAL_HD inline float history_normal_cos(float quality) {
  const double q = std::clamp(static_cast<double>(quality), 0.01, 1.0);
  return static_cast<float>(std::cos(glm::radians(std::min(25.8, 5.7 / q))));
}

// How far the mean origin of a pixel's history rays may lie from its surface point, in pixel
// footprints: 0.1 where q = 1 (the eye resolves single pixels there), 0.1 + 0.8·(1/q − 1) as the
// cells it resolves grow (1/q pixels), at most that at the filter's widest footprint.
FOVEAL_HD inline double history_reach_px(float quality) {
  const double q = std::clamp(static_cast<double>(quality), 1.0 / (1.0 + kMaxDenoiseRadius), 1.0);
  return 0.1 + 0.8 * (1.0 / q - 1.0);
}

// The history cap of a pixel, rays: H(E) = max(F, round(H·q)) frames of ceil(n/F) rays.
FOVEAL_HD inline float history_cap_rays(int rays, float quality, int temporal_frames, int history_frames) {
  const int f = temporal_frames > 1 ? temporal_frames : 1;
  const int frames = std::max(f, static_cast<int>(std::lround(history_frames * std::clamp(quality, 0.0f, 1.0f))));
  return static_cast<float>(frames) * static_cast<float>(refresh_rays(rays, f));
}

// The previous frame's counts and surfaces (host or device memory), and its camera.
struct HistoryView {
  CameraRays camera;
  float angle = 0;  // pixel_angle of its camera
  int width = 0, height = 0;
  const glm::vec3* position = nullptr;
  const glm::vec3* normal = nullptr;  // geometric
  const uint8_t* hit = nullptr;
  const float* open = nullptr;
  const float* cast = nullptr;
  const glm::vec3* origin = nullptr;  // Σ of the counted rays' origins
};

// The view of a history stored for `camera` at width × height, its arrays still to be set (host).
inline HistoryView history_view(const Camera& camera, int width, int height) {
  HistoryView h{CameraRays(camera, width, height)};
  h.angle = pixel_angle(camera.fov_deg, height);
  h.width = width;
  h.height = height;
  return h;
}

// The history of surface pixel i of `g` (a hit) into `out` (zero on entry); true when kept.
// `rays` and `quality`: the pixel's n(E) and q(E).
FOVEAL_HD inline bool reproject_pixel(const HistoryView& h, const SurfaceView& g, size_t i, float quality, int rays, int temporal_frames,
                                      const CountsView& out) {
  double px = 0, py = 0;
  float distance = 0;
  if (!h.camera.project(g.position[i], px, py, distance)) return false;
  if (!(px >= 0 && py >= 0 && px < h.width && py < h.height)) return false;
  // The four previous pixels around the point, bilinearly weighted, those that saw the same
  // surface (close normals, the point on their plane): their mean origin is the point's
  // own to first order, where one nearest pixel's is up to 0.7 px off
  const float footprint = h.angle * distance;
  const float normal_cos = history_normal_cos(quality);
  const double fx = px - 0.5, fy = py - 0.5;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const double ax = fx - x0, ay = fy - y0;
  double weight = 0, open = 0, cast = 0;
  glm::dvec3 origin_sum(0.0);
  for (int k = 0; k < 4; ++k) {
    const int u = x0 + (k & 1), v = y0 + (k >> 1);
    if (u < 0 || v < 0 || u >= h.width || v >= h.height) continue;
    const size_t j = static_cast<size_t>(v) * h.width + u;
    if (!h.hit[j] || !(h.cast[j] > 0)) continue;
    if (glm::dot(g.geo_normal[i], h.normal[j]) < normal_cos) continue;
    if (std::fabs(glm::dot(g.position[i] - h.position[j], h.normal[j])) > 2.0f * footprint) continue;
    const double b = ((k & 1) ? ax : 1.0 - ax) * ((k >> 1) ? ay : 1.0 - ay);
    if (!(b > 0)) continue;
    weight += b;
    open += b * h.open[j];
    cast += b * h.cast[j];
    origin_sum += b * glm::dvec3(h.origin[j]);
  }
  if (!(weight > 0)) return false;
  open /= weight;
  cast /= weight;
  origin_sum /= weight;
  // Where the history's rays were cast from: their mean origin, which drifts from the point
  // as the camera moves. To first order the estimate's bias is that offset times the
  // gradient of V, so the history is weighed down until the mean origin after this frame's
  // m = n/F rays at the point lies within the reach the eye allows: 0.1 px where q = 1,
  // growing as the cells it resolves (1/q px) grow.
  const glm::vec3 origin = glm::vec3(origin_sum / cast);
  const double d = glm::length(g.position[i] - origin) / fmaxf(footprint, 1e-12f);
  const double reach = history_reach_px(quality);
  float scale = 1.0f;
  if (d > reach) {
    const double m = refresh_rays(rays, temporal_frames);
    scale = static_cast<float>(fmin(1.0, m * reach / ((d - reach) * cast)));
    if (!(scale * cast >= 1.0)) return false;  // less than a ray: none
  }
  out.open[i] = static_cast<float>(scale * open);
  out.cast[i] = static_cast<float>(scale * cast);
  out.origin_sum[i] = glm::vec3(static_cast<double>(scale) * origin_sum);
  return true;
}

// What pixel i keeps for the next frame: its counts capped at `cap` rays (scaled down, V
// unchanged), and the Σ of their origins (`origin_sum` may be null: all cast at `position`).
FOVEAL_HD inline void history_of_pixel(float cap, float open, float cast, const glm::vec3* origin_sum, size_t i, glm::vec3 position,
                                       float& kept_open, float& kept_cast, glm::vec3& kept_origin) {
  const float scale = cast > cap ? cap / cast : 1.0f;
  kept_open = open * scale;
  kept_cast = cast * scale;
  kept_origin = origin_sum ? origin_sum[i] * scale : cast * scale * position;
}

// ---- The edge-stopping filter ------------------------------------------------------------------

// The footprint radius a pixel may pool over, pixels: round(radius·(1/q − 1)) up to kMaxDenoiseRadius
// (the eye resolves cells of 1/q pixels; 0 where q = 1: the fovea is never filtered).
FOVEAL_HD inline int denoise_max_radius(float quality, double denoise_radius) {
  if (!(quality > 0)) return kMaxDenoiseRadius;
  // The eye resolves cells of 1/q pixels (q = f_c(E)/f_c(0), and at q = 1 every pixel): pooling
  // within radius·(1/q − 1) pixels of a cell's neighbours, none where q = 1
  const double r = std::round(denoise_radius * (1.0 / quality - 1.0));
  return static_cast<int>(std::clamp(r, 0.0, static_cast<double>(kMaxDenoiseRadius)));
}

// The filter at pixel (x, y) of `g` with counts `open`/`cast` and q(E) `quality`: true, with the
// pooled visibility in `v`, where the pixel's standard error exceeds τ(E) = tau_fovea / q and the
// eye's cells are wider than a pixel; false where it is left alone. `angle`: pixel_angle.
FOVEAL_HD inline bool denoise_pixel(const SurfaceView& g, const float* quality, const float* open_count, const float* cast_count, int x,
                                    int y, float angle, float tau_fovea, double denoise_radius, float& v) {
  constexpr float kSameNormal = 0.9f;  // cos 25.8°: the filter pools only pixels whose normals are this close
  constexpr float kAlbedoSigma = 0.15f;
  // Range weight: neighbours whose estimate differs from the pixel's by more than k(E) of their
  // combined standard error are weighed down as another AO (SVGF's luminance edge-stopping,
  // normalised by the estimates' variance), k(E) = 1/√q(E) widening as acuity falls. Measured
  // (acuity-weighted error × the reference's noise; none / k = 1 / 1/√q / 1/q): gaze off the dragon,
  // its crevices at 5–20° (420×262 orbit, temporal+adaptive+denoise) 1.53 / 1.17 / 1.22 / 1.28;
  // one frame at γ 4, the centre gaze, 1.57 / 1.71 / 1.63 / 1.60; gaze on the dragon 1.01 in all.
  constexpr float kRangeSigma = 1.0f;
  const size_t i = static_cast<size_t>(y) * g.width + x;
  const float cast = cast_count[i];
  if (!g.hit(i) || !(cast > 0)) return false;
  // Is the pixel noisier than its eccentricity allows?
  const float se = visibility_standard_error(open_count[i], cast), spread = se * se * cast;
  const float tau = quality[i] > 0 ? tau_fovea / quality[i] : INFINITY;
  if (se <= tau) return false;
  // Just wide enough to pool the rays it lacks: (2r+1)² pixels of about its own count
  const float lacking = spread / (tau * tau) / cast;
  const int widest = denoise_max_radius(quality[i], denoise_radius);
  if (widest == 0) return false;
  const int radius = std::clamp(static_cast<int>(std::ceil(0.5f * std::sqrt(lacking))), 1, widest);
  const float sigma2 = static_cast<float>(radius * radius);
  const glm::vec3 pi = g.position[i], ni = g.normal[i], ai = g.albedo[i];
  const float vi = open_count[i] / cast;
  const float range2 = kRangeSigma * kRangeSigma / quality[i];  // k(E)² (q > 0: τ is finite here)
  const float footprint = angle * g.depth[i];
  float open_sum = 0, cast_sum = 0;
  for (int yy = std::max(0, y - radius); yy <= std::min(g.height - 1, y + radius); ++yy)
    for (int xx = std::max(0, x - radius); xx <= std::min(g.width - 1, x + radius); ++xx) {
      const size_t j = static_cast<size_t>(yy) * g.width + xx;
      if (!g.hit(j) || !(cast_count[j] > 0)) continue;
      // Hard edges: a crease (normals apart) or a depth step (off the pixel's plane)
      if (glm::dot(ni, g.normal[j]) < kSameNormal) continue;
      const float d2 = static_cast<float>((xx - x) * (xx - x) + (yy - y) * (yy - y));
      const float plane = std::fabs(glm::dot(g.position[j] - pi, ni));
      if (plane > 0.5f * footprint * fmaxf(1.0f, std::sqrt(d2))) continue;
      const glm::vec3 da = g.albedo[j] - ai;
      // Range: estimates further apart than their noise explains are another AO (a crevice)
      const float vj = open_count[j] / cast_count[j], sej = visibility_standard_error(open_count[j], cast_count[j]);
      const float dv = vj - vi, var = range2 * (se * se + sej * sej);
      const float w = std::exp(-0.5f * d2 / sigma2 - 0.5f * glm::dot(da, da) / (kAlbedoSigma * kAlbedoSigma) - 0.5f * dv * dv / var);
      open_sum += w * open_count[j];
      cast_sum += w * cast_count[j];
    }
  if (!(cast_sum > 0)) return false;
  v = open_sum / cast_sum;
  return true;
}

}  // namespace foveal
