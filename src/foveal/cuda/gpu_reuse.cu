// foveal/cuda/gpu_reuse.cu — quality per ray on the GPU: the CPU's passes (render.cpp's
// trace_ao_counts, reuse.cpp's AoHistory and filter) as kernels, one thread per pixel, whose
// bodies (cuda/reuse_kernels.h) call the CPU's own per-pixel functions (render/reuse_pixel.h).
// Counts, the filter's output and the history stay on the GPU; a temporal sequence keeps its
// history in the Renderer between frames.
//
// The AO pass runs in rounds, since a pixel's next round depends on what its earlier rays found.
// With the balanced schedule (the default) each round is a launch over every pixel's rays of that
// round laid end to end by their prefix sum, as the paper's balanced pass lays a frame's; with the
// per-pixel schedule one thread runs its own pixel's rounds. On an H200 (the dragon at 840x525)
// the first's AO took 13.9 ms for adaptive rays with the filter and 3.4 ms for a temporal frame,
// the second's 31.2 and 7.7 (1.3–1.5 G rays/s, where the paper's balanced pass traces 5.3). Every
// sum is of integers, or per pixel in one thread, so a frame is the same on every run and with
// either schedule.
#include "foveal/cuda/gpu_internal.cuh"

#include "foveal/cuda/reuse_kernels.h"

#include <cub/device/device_scan.cuh>
#include <cuda_runtime.h>

#include <algorithm>

namespace foveal::gpu::detail {
namespace {

SurfaceView surface_view(const Renderer::Impl& m, int width, int height) {
  return {m.prim.get(), m.position.get(), m.normal.get(), m.geo_normal.get(), m.albedo.get(), m.depth.get(), width, height};
}

__global__ void reproject_kernel(HistoryView h, SurfaceView g, const float* quality, const uint16_t* rays, int temporal_frames,
                                 CountsView out, FrameCounters* counters) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= static_cast<size_t>(g.width) * g.height) return;
  if (reproject_body(h, g, quality, rays, temporal_frames, out, i)) atomicAdd(&counters->history_pixels, 1ULL);
}

__global__ void ao_reuse_kernel(AoReuseArgs a, FrameCounters* counters) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= static_cast<size_t>(a.g.width) * a.g.height) return;
  const uint32_t traced = ao_reuse_body(a, i);
  if (traced) atomicAdd(&counters->total_rays, static_cast<unsigned long long>(traced));
}

// The balanced schedule's rounds: each pixel's plan and first round's rays
__global__ void ao_rounds_begin_kernel(AoReuseArgs a, AoRoundState* state, unsigned long long* round_rays, uint32_t* blocked) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= static_cast<size_t>(a.g.width) * a.g.height) return;
  round_rays[i] = ao_rounds_begin_body(a, state, i);
  blocked[i] = 0;
}

__global__ void ao_rounds_total_kernel(const unsigned long long* offset, const unsigned long long* round_rays, size_t pixels,
                                       unsigned long long* total) {
  *total = offset[pixels - 1] + round_rays[pixels - 1];
}

// One round's rays of every pixel, laid end to end: kAoChunk consecutive rays per thread, a
// grid-stride loop (the paper's balanced pass, gpu_renderer.cu); a thread's chunk that leaves its
// pixel finds the next one with rays by binary search too
__global__ void ao_rounds_trace_kernel(AoReuseArgs a, const AoRoundState* state, const unsigned long long* offset,
                                       const unsigned long long* round_rays, size_t pixels, const unsigned long long* total_rays,
                                       uint32_t* blocked) {
  const unsigned long long total = *total_rays;
  const unsigned long long chunks = (total + kAoChunk - 1) / kAoChunk;
  for (unsigned long long c = blockIdx.x * static_cast<unsigned long long>(blockDim.x) + threadIdx.x; c < chunks;
       c += static_cast<unsigned long long>(gridDim.x) * blockDim.x) {
    unsigned long long r = c * kAoChunk;
    const unsigned long long end = min(r + kAoChunk, total);
    size_t pixel = holder_of(offset, 0, pixels, r);
    unsigned long long pixel_end = offset[pixel] + round_rays[pixel];
    AoPixelRays rays = ao_round_rays(a, state[pixel], pixel);
    uint32_t first = state[pixel].rounds.offset + state[pixel].rounds.cast;
    uint32_t count = 0;
    for (; r < end; ++r) {
      if (r >= pixel_end) {
        if (count) atomicAdd(&blocked[pixel], count);
        count = 0;
        // The next pixel with rays this round: a later round's are few and scattered, and walking
        // the pixels between them one by one took milliseconds a round
        if (round_rays[++pixel] == 0) pixel = holder_of(offset, pixel, pixels, r);
        pixel_end = offset[pixel] + round_rays[pixel];
        rays = ao_round_rays(a, state[pixel], pixel);
        first = state[pixel].rounds.offset + state[pixel].rounds.cast;
      }
      count += bvh_trace<true>(a.bvh, rays(first + static_cast<uint32_t>(r - offset[pixel])), nullptr) ? 1U : 0U;
    }
    if (count) atomicAdd(&blocked[pixel], count);
  }
}

// Each pixel that cast a round judged on all its rays: its next round's rays, or done
__global__ void ao_rounds_next_kernel(AoReuseArgs a, AoRoundState* state, unsigned long long* round_rays, uint32_t* blocked,
                                      FrameCounters* counters) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= static_cast<size_t>(a.g.width) * a.g.height || round_rays[i] == 0) return;
  uint32_t traced = 0;
  round_rays[i] = ao_rounds_next_body(a, state, blocked[i], i, &traced);
  blocked[i] = 0;
  if (traced) atomicAdd(&counters->total_rays, static_cast<unsigned long long>(traced));
}

// V, and the q = 1 pixels' Σ V for the `auto` ambient constant in fixed point (exact in any order)
__global__ void counts_visibility_kernel(SurfaceView g, const float* quality, const uint16_t* rays, const float* open, const float* cast,
                                         float* visibility, FrameCounters* counters) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= static_cast<size_t>(g.width) * g.height) return;
  if (counts_visibility_body(g, quality, rays, open, cast, visibility, i)) {
    atomicAdd(&counters->fovea_visibility,
              static_cast<unsigned long long>(llrint(static_cast<double>(visibility[i]) * kFoveaVisibilityUnit)));
    atomicAdd(&counters->fovea_pixels, 1ULL);
  }
}

__global__ void denoise_kernel(DenoiseArgs a, FrameCounters* counters) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= a.g.width || y >= a.g.height) return;
  if (denoise_body(a, x, y)) atomicAdd(&counters->denoised_pixels, 1ULL);
}

__global__ void store_history_kernel(StoreArgs a) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i < static_cast<size_t>(a.g.width) * a.g.height) store_history_body(a, i);
}

}  // namespace

float* run_reuse_passes(Renderer::Impl& m, const ReuseFrame& frame) {
  const RenderParams& p = *frame.params;
  const AoReuseParams& reuse = p.reuse;
  const size_t n = frame.pixels;
  const int w = p.width, h = p.height;
  const bool temporal = reuse.temporal;
  Renderer::Impl::History& history = m.history;
  m.count_open.reserve(n);
  m.count_cast.reserve(n);
  m.traced.reserve(n);
  if (temporal) m.count_origin.reserve(n);
  if (reuse.denoise) m.filtered.reserve(n);
  const SurfaceView g = surface_view(m, w, h);
  const CountsView counts{m.count_open.get(), m.count_cast.get(), temporal ? m.count_origin.get() : nullptr};
  const unsigned blocks = blocks_for(n, 128);
  // The history reprojected to this frame's surface points, or none
  if (temporal && history.frames > 0) {
    HistoryView view = history_view(history.camera, history.width, history.height);
    view.position = history.position.get();
    view.normal = history.normal.get();
    view.hit = history.hit.get();
    view.open = history.open.get();
    view.cast = history.cast.get();
    view.origin = history.origin.get();
    reproject_kernel<<<blocks, 128>>>(view, g, m.quality.get(), m.rays.get(), reuse.temporal_frames, counts, m.counters.get());
    FOVEAL_CUDA_LAUNCHED("reprojection");
  } else {
    FOVEAL_CUDA_CHECK(cudaMemset(counts.open, 0, n * sizeof(float)));
    FOVEAL_CUDA_CHECK(cudaMemset(counts.cast, 0, n * sizeof(float)));
    if (counts.origin_sum) FOVEAL_CUDA_CHECK(cudaMemset(counts.origin_sum, 0, n * sizeof(glm::vec3)));
  }
  m.events.record(3);
  // The AO pass in rounds, on the history
  const AoSampling sampling = ao_sampling(reuse, temporal ? history.frames : 0);
  const AoReuseArgs ao{m.bvh_view(),   g,        m.quality.get(),   m.rays.get(), m.sobol.get(), counts,
                       m.traced.get(), sampling, frame.ao_distance, m.epsilon,    p.seed};
  if (m.schedule == AoSchedule::balanced) {
    // A launch per round (at most ten or so: rounds double a pixel's rays, and a contradicted
    // history restarts a pixel once), each round's total read back to know whether one is left
    m.round_state.reserve(n);
    m.round_rays.reserve(1);
    ao_rounds_begin_kernel<<<blocks, 128>>>(ao, m.round_state.get(), m.ray_count.get(), m.blocked.get());
    FOVEAL_CUDA_LAUNCHED("ambient occlusion (quality per ray): plans");
    for (int round = 0;; ++round) {
      if (round > 64) throw Error("gpu::Renderer: the AO pass's rounds did not end (an internal error)");
      size_t temp_bytes = m.scan_temp_bytes;
      FOVEAL_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(m.scan_temp.get(), temp_bytes, m.ray_count.get(), m.offset.get(), n));
      ao_rounds_total_kernel<<<1, 1>>>(m.offset.get(), m.ray_count.get(), n, m.round_rays.get());
      FOVEAL_CUDA_LAUNCHED("ambient occlusion (quality per ray): round total");
      unsigned long long rays = 0;
      m.round_rays.download(&rays, 1);
      if (rays == 0) break;
      const unsigned grid = std::min<unsigned>(static_cast<unsigned>(m.ao_grid), blocks_for((rays + kAoChunk - 1) / kAoChunk, 128));
      ao_rounds_trace_kernel<<<grid, 128>>>(ao, m.round_state.get(), m.offset.get(), m.ray_count.get(), n, m.round_rays.get(),
                                            m.blocked.get());
      FOVEAL_CUDA_LAUNCHED("ambient occlusion (quality per ray): a round");
      ao_rounds_next_kernel<<<blocks, 128>>>(ao, m.round_state.get(), m.ray_count.get(), m.blocked.get(), m.counters.get());
      FOVEAL_CUDA_LAUNCHED("ambient occlusion (quality per ray): next rounds");
    }
  } else {
    ao_reuse_kernel<<<blocks, 128>>>(ao, m.counters.get());
    FOVEAL_CUDA_LAUNCHED("ambient occlusion (quality per ray)");
  }
  m.events.record(4);
  // Visibility, the filter, and what the next frame keeps
  counts_visibility_kernel<<<blocks_for(n, 256), 256>>>(g, m.quality.get(), m.rays.get(), counts.open, counts.cast, m.visibility.get(),
                                                        m.counters.get());
  FOVEAL_CUDA_LAUNCHED("visibility");
  float* visibility = m.visibility.get();
  if (reuse.denoise) {
    const dim3 block2d(16, 8), grid2d((w + 15) / 16, (h + 7) / 8);
    const DenoiseArgs denoise{g,
                              m.quality.get(),
                              counts.open,
                              counts.cast,
                              pixel_angle(frame.camera->fov_deg, h),
                              reuse.tau_fovea(),
                              reuse.denoise_radius,
                              m.visibility.get(),
                              m.filtered.get()};
    denoise_kernel<<<grid2d, block2d>>>(denoise, m.counters.get());
    FOVEAL_CUDA_LAUNCHED("denoising");
    visibility = m.filtered.get();
  }
  if (temporal) {
    // The reprojection above has read the last frame's history: its buffers may be replaced
    for (auto* a : {&history.position, &history.normal, &history.origin}) a->reserve(n);
    history.hit.reserve(n);
    history.open.reserve(n);
    history.cast.reserve(n);
    const StoreArgs store{g,
                          m.quality.get(),
                          m.rays.get(),
                          reuse.temporal_frames,
                          reuse.history_frames,
                          counts,
                          history.position.get(),
                          history.normal.get(),
                          history.origin.get(),
                          history.hit.get(),
                          history.open.get(),
                          history.cast.get()};
    store_history_kernel<<<blocks, 128>>>(store);
    FOVEAL_CUDA_LAUNCHED("history");
    history.camera = *frame.camera;
    history.width = w;
    history.height = h;
    ++history.frames;
  }
  m.events.record(5);
  return visibility;
}

}  // namespace foveal::gpu::detail
