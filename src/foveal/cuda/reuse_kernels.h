// foveal/cuda/reuse_kernels.h — the bodies of the CUDA backend's quality-per-ray kernels, one
// pixel each, over the shared BVH2 traversal (trace/bvh.h) and the per-pixel functions of
// render/reuse_pixel.h. No CUDA types: gpu_reuse.cu launches them one GPU thread per pixel, and
// the tests run the same bodies on the CPU over host memory, so the GPU's passes are checked
// against the CPU renderer on machines without a GPU.
#pragma once

#include "foveal/render/reuse_pixel.h"
#include "foveal/trace/bvh.h"

#include <cmath>
#include <cstdint>

namespace foveal::gpu {

// The history of pixel i reprojected into `out` (zero where none is kept); true when kept.
FOVEAL_HD inline bool reproject_body(const HistoryView& h, const SurfaceView& g, const float* quality, const uint16_t* rays,
                                     int temporal_frames, const CountsView& out, size_t i) {
  out.open[i] = out.cast[i] = 0.0f;
  out.origin_sum[i] = glm::vec3(0.0f);
  return g.hit(i) && reproject_pixel(h, g, i, quality[i], rays[i], temporal_frames, out);
}

struct AoReuseArgs {
  BvhView bvh;
  SurfaceView g;
  const float* quality;
  const uint16_t* rays;
  const uint32_t* sobol;  // sobol_table_2d() or its device copy
  CountsView counts;      // history on entry (zero without), history + this frame's rays on return
  uint16_t* traced;
  AoSampling sampling;
  float ao_distance, epsilon;
  uint64_t seed;
};

// Pixel i's AO rays in rounds (render.cpp's trace_ao_counts for one pixel): cast a round, judge
// the pixel on all its rays (drop a contradicted history, stop at the standard error its
// eccentricity allows), cast the next. Returns the rays traced.
FOVEAL_HD inline uint32_t ao_reuse_body(const AoReuseArgs& a, size_t i) {
  const int n = a.rays[i];
  if (!a.g.hit(i) || n == 0) {
    a.traced[i] = 0;
    return 0;
  }
  const AoPixelPlan plan = plan_ao_pixel(n, a.counts.cast[i], a.sampling, a.seed);
  const AoPixelRays pixel_rays(a.g.position[i], a.g.geo_normal[i], a.epsilon, a.ao_distance, plan.seed,
                               static_cast<uint32_t>(i % a.g.width), static_cast<uint32_t>(i / a.g.width), a.sobol);
  AoPixelRounds r(plan, n);
  do {
    while (r.cast < r.round_end) r.blocked += bvh_trace<true>(a.bvh, pixel_rays(r.offset + r.cast++), nullptr) ? 1U : 0U;
  } while (r.next_round(a.counts, i, a.quality[i], a.sampling));
  a.traced[i] = r.finish(a.counts, i, a.g.position[i]);
  return r.dropped + r.cast;
}

// The same rounds with every pixel's round laid end to end (gpu_reuse.cu's balanced schedule: a
// launch per round over all pixels' rays, as the paper's balanced pass lays a frame's). Between
// launches each pixel keeps its rounds and its sequence's scramble; the rays and every count are
// ao_reuse_body's, since a round's blocked rays are an integer sum in any order.
struct AoRoundState {
  AoPixelRounds rounds;
  uint64_t seed = 0;  // AoPixelPlan::seed
};

// Pixel i's plan: its state, and the rays of its first round (0: none, and pixel i is done).
// (A pixel with rays casts at least one in its first round: plan_ao_pixel's limit is at least
// ceil(n/F) ≥ 1.)
FOVEAL_HD inline uint32_t ao_rounds_begin_body(const AoReuseArgs& a, AoRoundState* state, size_t i) {
  const int n = a.rays[i];
  if (!a.g.hit(i) || n == 0) {
    a.traced[i] = 0;
    state[i].rounds = AoPixelRounds();
    return 0;
  }
  const AoPixelPlan plan = plan_ao_pixel(n, a.counts.cast[i], a.sampling, a.seed);
  state[i].rounds = AoPixelRounds(plan, n);
  state[i].seed = plan.seed;
  return state[i].rounds.round_end - state[i].rounds.cast;
}

// Pixel i's rays (ray k of its sequence: the round's first is rounds.offset + rounds.cast).
FOVEAL_HD inline AoPixelRays ao_round_rays(const AoReuseArgs& a, const AoRoundState& state, size_t i) {
  return AoPixelRays(a.g.position[i], a.g.geo_normal[i], a.epsilon, a.ao_distance, state.seed, static_cast<uint32_t>(i % a.g.width),
                     static_cast<uint32_t>(i / a.g.width), a.sobol);
}

// After pixel i's round, `blocked` of its rays blocked: the pixel judged on all its rays. Returns
// the rays of its next round, or 0 once it is done; then its counts and traced[i] are final and
// *traced holds the rays it traced this frame.
FOVEAL_HD inline uint32_t ao_rounds_next_body(const AoReuseArgs& a, AoRoundState* state, uint32_t blocked, size_t i, uint32_t* traced) {
  AoPixelRounds& r = state[i].rounds;
  r.blocked += blocked;
  r.cast = r.round_end;
  if (r.next_round(a.counts, i, a.quality[i], a.sampling)) return r.round_end - r.cast;
  a.traced[i] = r.finish(a.counts, i, a.g.position[i]);
  *traced = r.dropped + r.cast;
  return 0;
}

// V = open / cast of pixel i (1 without rays); true where it counts towards the `auto` ambient
// constant (a q = 1 pixel with rays).
FOVEAL_HD inline bool counts_visibility_body(const SurfaceView& g, const float* quality, const uint16_t* rays, const float* open,
                                             const float* cast, float* visibility, size_t i) {
  visibility[i] = cast[i] > 0 ? open[i] / cast[i] : 1.0f;
  return g.hit(i) && quality[i] >= 1.0f && rays[i] > 0;
}

struct DenoiseArgs {
  SurfaceView g;
  const float* quality;
  const float* open;
  const float* cast;
  float angle;  // pixel_angle of the camera
  float tau_fovea;
  double radius;  // AoReuseParams::denoise_radius
  const float* visibility;
  float* out;
};

// The filter at pixel (x, y) into `out` (its own V where it is left alone); true when changed.
FOVEAL_HD inline bool denoise_body(const DenoiseArgs& a, int x, int y) {
  const size_t i = static_cast<size_t>(y) * a.g.width + x;
  float v = 0;
  if (denoise_pixel(a.g, a.quality, a.open, a.cast, x, y, a.angle, a.tau_fovea, a.radius, v) && v != a.visibility[i]) {
    a.out[i] = v;
    return true;
  }
  a.out[i] = a.visibility[i];
  return false;
}

struct StoreArgs {
  SurfaceView g;
  const float* quality;
  const uint16_t* rays;
  int temporal_frames, history_frames;
  CountsView counts;
  glm::vec3 *position, *normal, *origin;
  uint8_t* hit;
  float *open, *cast;
};

// What pixel i leaves for the next frame (AoHistory::store for one pixel).
FOVEAL_HD inline void store_history_body(const StoreArgs& a, size_t i) {
  a.hit[i] = a.g.hit(i) ? 1 : 0;
  a.position[i] = a.g.position[i];
  a.normal[i] = a.g.geo_normal[i];
  history_of_pixel(history_cap_rays(a.rays[i], a.quality[i], a.temporal_frames, a.history_frames), a.counts.open[i], a.counts.cast[i],
                   a.counts.origin_sum, i, a.g.position[i], a.open[i], a.cast[i], a.origin[i]);
}

}  // namespace foveal::gpu
