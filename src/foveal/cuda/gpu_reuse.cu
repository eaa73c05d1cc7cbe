// foveal/cuda/gpu_reuse.cu — quality per ray on the GPU: the CPU's passes (render.cpp's
// trace_ao_counts, reuse.cpp's AoHistory and filter) as kernels, one thread per pixel, whose
// bodies (cuda/reuse_kernels.h) call the CPU's own per-pixel functions (render/reuse_pixel.h).
// Counts, the filter's output and the history stay on the GPU; a temporal sequence keeps its
// history in the Renderer between frames.
//
// The AO pass runs a pixel's rounds in its own thread (the per-pixel schedule): a pixel's rounds
// depend on what its earlier rays found, so the rays cannot be laid out before the pass as the
// paper's balanced schedule lays them out. Every sum is of integers, or per pixel in one thread,
// so a frame is the same on every run.
#include "foveal/cuda/gpu_internal.cuh"

#include "foveal/cuda/reuse_kernels.h"

#include <cuda_runtime.h>

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
  ao_reuse_kernel<<<blocks, 128>>>(ao, m.counters.get());
  FOVEAL_CUDA_LAUNCHED("ambient occlusion (quality per ray)");
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
