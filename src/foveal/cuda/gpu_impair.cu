// foveal/cuda/gpu_impair.cu — an impaired eye's passes (impair/impairments.h) as kernels over the
// blurred image on the GPU.
//
// The operations and their order are ImpairmentPasses::apply's, and every output pixel is computed
// with the CPU's rules: the models' own (field_loss_db, metamorphopsia_displacement, cvd_apply,
// retinotopy_between) and OpenCV's resampling as impair/resample.h computes it (pyrDown, pyrUp,
// resize, remap). This file is compiled without fused multiply-adds (src/foveal/CMakeLists.txt), as
// the CPU's code is, so that the two round alike. What differs is how the glare's convolution is
// summed: on the CPU a DFT of its coarse grid, here directly over the grid (at most 160 columns:
// 14,400 × 14,400 products at 1280×720), in slices of rows added up in a fixed order.
#include "foveal/cuda/gpu_internal.cuh"

#include "foveal/impair/resample.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace foveal::gpu::detail {
namespace {

constexpr int kSliceRows = 8;     // rows of the glare's grid each slice of the convolution sums
constexpr int kMaxColumns = 160;  // the glare grid's widest (glare_grid)

// ---- Media ---------------------------------------------------------------------------------------

__global__ void area_down_kernel(const float* src, int sw, int sh, float* dst, int dw, int dh) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dw || y >= dh) return;
  for (int c = 0; c < 3; ++c) dst[(static_cast<size_t>(y) * dw + x) * 3 + c] = resample::resize_area_at(src, sw, sh, 3, dw, dh, x, y, c);
}

// One slice of rows of the direct convolution: partial[slice][pixel] = Σ over the slice's grid cells
// of the cell's light × the kernel at the offset between the two.
__global__ void glare_slice_kernel(const float* small, int w, int h, const float* kernel, float* partial) {
  __shared__ float rows[kSliceRows * kMaxColumns * 3];
  const int j0 = blockIdx.z * kSliceRows, j1 = min(h, j0 + kSliceRows);
  const int count = (j1 - j0) * w * 3;
  const int tid = threadIdx.y * blockDim.x + threadIdx.x, threads = blockDim.x * blockDim.y;
  for (int i = tid; i < count; i += threads) rows[i] = small[static_cast<size_t>(j0) * w * 3 + i];
  __syncthreads();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  const int kw = 2 * w - 1;
  float r = 0, g = 0, b = 0;
  for (int j = j0; j < j1; ++j) {
    const float* k = kernel + static_cast<size_t>(y - j + h - 1) * kw + (x + w - 1);  // k[-i]: the offset x − i
    const float* s = rows + (j - j0) * w * 3;
    for (int i = 0; i < w; ++i) {
      const float kv = k[-i];
      r += s[i * 3] * kv;
      g += s[i * 3 + 1] * kv;
      b += s[i * 3 + 2] * kv;
    }
  }
  float* out = partial + (static_cast<size_t>(blockIdx.z) * w * h + static_cast<size_t>(y) * w + x) * 3;
  out[0] = r;
  out[1] = g;
  out[2] = b;
}

__global__ void glare_sum_kernel(const float* partial, int slices, size_t values, float* scattered) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= values) return;
  float sum = 0;
  for (int s = 0; s < slices; ++s) sum += partial[s * values + i];
  scattered[i] = sum;
}

// out = (1 − η)·I + the scattered light upsampled (glare), then × the lens's transmittance (yellowing)
__global__ void media_kernel(float* img, int w, int h, const float* scattered, int sw, int sh, float keep, bool glare, bool yellow,
                             glm::vec3 transmittance) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  float* p = img + (static_cast<size_t>(y) * w + x) * 3;
  for (int c = 0; c < 3; ++c) {
    float v = p[c];
    if (glare) v = keep * v + resample::resize_linear_at(scattered, sw, sh, 3, w, h, x, y, c);
    if (yellow) v *= transmittance[c];
    p[c] = v;
  }
}

// ---- Retina --------------------------------------------------------------------------------------

// The distortion on every 4th pixel (pixels of the image's grid clamped to its last row and column),
// and the rectangle of grid points where it is not zero.
__global__ void distortion_grid_kernel(const glm::vec2* retina, int columns, int rows, int w, int h, MetamorphopsiaBumps bumps, double ppd,
                                       float* gx, float* gy, int* box) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x, j = blockIdx.y * blockDim.y + threadIdx.y;
  if (i >= columns || j >= rows) return;
  constexpr int step = RetinotopyGrid::kStep;
  const int x = min(i * step, w - 1), y = min(j * step, h - 1);
  const glm::vec2 f = retinotopy_between(retina, columns, x, y);
  const glm::dvec2 d = metamorphopsia_displacement(bumps, f.x, f.y);
  const float dx = static_cast<float>(d.x * ppd), dy = static_cast<float>(-d.y * ppd);
  gx[static_cast<size_t>(j) * columns + i] = dx;
  gy[static_cast<size_t>(j) * columns + i] = dy;
  if (dx != 0.0f || dy != 0.0f) {
    atomicMin(&box[0], i);
    atomicMax(&box[1], i);
    atomicMin(&box[2], j);
    atomicMax(&box[3], j);
  }
}

__global__ void distort_kernel(const float* src, float* img, int w, int h, const float* gx, const float* gy, int columns, int x0, int y0,
                               int rw, int rh) {
  const int rx = blockIdx.x * blockDim.x + threadIdx.x, ry = blockIdx.y * blockDim.y + threadIdx.y;
  if (rx >= rw || ry >= rh) return;
  constexpr int step = RetinotopyGrid::kStep;
  const int x = x0 + rx, y = y0 + ry, i = x / step, j = y / step;
  const float tx = float(x - i * step) / step, ty = float(y - j * step) / step;
  auto lerp2 = [&](const float* m) {
    const size_t a = static_cast<size_t>(j) * columns + i, b = a + columns;
    return (1 - ty) * ((1 - tx) * m[a] + tx * m[a + 1]) + ty * ((1 - tx) * m[b] + tx * m[b + 1]);
  };
  const float mx = static_cast<float>(x) + lerp2(gx), my = static_cast<float>(y) + lerp2(gy);
  float* p = img + (static_cast<size_t>(y) * w + x) * 3;
  for (int c = 0; c < 3; ++c) p[c] = resample::remap_linear_at(src, w, h, 3, mx, my, c);
}

__global__ void loss_kernel(const glm::vec2* retina, int columns, int w, int h, FieldMapView map, float* loss) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  const glm::vec2 f = retinotopy_between(retina, columns, x, y);
  loss[static_cast<size_t>(y) * w + x] = static_cast<float>(field_loss_db(map, f.x, f.y, FieldMap::kExtentDeg, FieldMap::kStepDeg));
}

__global__ void pyr_down_kernel(const float* src, int sw, int sh, int cn, float* dst, int dw, int dh) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dw || y >= dh) return;
  for (int c = 0; c < cn; ++c) dst[(static_cast<size_t>(y) * dw + x) * cn + c] = resample::pyr_down_at(src, sw, sh, cn, x, y, c);
}

// One level of the band-limited contrast (or blur): the level's band g − up(g below), weighted by
// the loss there, added to the output from below upsampled (apply_field_loss's loop at level k).
__global__ void band_kernel(const float* g, int w, int h, const float* g_below, const float* out_below, int bw, int bh, const float* loss,
                            int lw, int lh, int level, bool contrast, float* dst) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  const float l = level == 0 ? loss[static_cast<size_t>(y) * w + x] : resample::resize_linear_at(loss, lw, lh, 1, w, h, x, y, 0);
  const float ln10_10 = static_cast<float>(2.302585092994046 / 10.0);
  const float weight = l == 0.0f ? 1.0f : contrast ? expf(-l * ln10_10) : fminf(fmaxf((level + 1.0f) - l / 6.0f, 0.0f), 1.0f);
  const size_t i = (static_cast<size_t>(y) * w + x) * 3;
  for (int c = 0; c < 3; ++c) {
    const float up_g = resample::pyr_up_at(g_below, bw, bh, 3, x, y, c), up_o = resample::pyr_up_at(out_below, bw, bh, 3, x, y, c);
    dst[i + c] = up_o + weight * (g[i + c] - up_g);
  }
}

// The remaining sensitivity 10^(−L/10); with `premultiplied`, the image × it (filling-in's push).
__global__ void sensitivity_kernel(const float* img, const float* loss, size_t pixels, float* m, float* premultiplied) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= pixels) return;
  const float s = expf(loss[i] * static_cast<float>(-2.302585092994046 / 10.0));
  m[i] = s;
  if (premultiplied)
    for (int c = 0; c < 3; ++c) premultiplied[i * 3 + c] = img[i * 3 + c] * s;
}

// Sums of each channel in double, one per block (then added up in block order on the host).
__global__ void channel_sums_kernel(const float* img, size_t pixels, double* sums) {
  __shared__ double part[3][256];
  double s[3] = {0, 0, 0};
  for (size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x; i < pixels; i += static_cast<size_t>(gridDim.x) * blockDim.x)
    for (int c = 0; c < 3; ++c) s[c] += img[i * 3 + c];
  for (int c = 0; c < 3; ++c) part[c][threadIdx.x] = s[c];
  __syncthreads();
  for (int stride = blockDim.x / 2; stride > 0; stride /= 2) {
    if (threadIdx.x < stride)
      for (int c = 0; c < 3; ++c) part[c][threadIdx.x] += part[c][threadIdx.x + stride];
    __syncthreads();
  }
  if (threadIdx.x == 0)
    for (int c = 0; c < 3; ++c) sums[blockIdx.x * 3 + c] = part[c][0];
}

__global__ void grey_kernel(float* img, const float* m, size_t pixels, glm::vec3 mean) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= pixels) return;
  const float keep = m[i], rest = 1.0f - m[i];
  for (int c = 0; c < 3; ++c) img[i * 3 + c] = img[i * 3 + c] * keep + mean[c] * rest;
}

// Filling-in's coarsest level: the premultiplied colour over its weight (at least 1e-6).
__global__ void fill_top_kernel(const float* colour, const float* weight, size_t pixels, float* fill) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= pixels) return;
  const float inv = 1.0f / fmaxf(weight[i], 1e-6f);
  for (int c = 0; c < 3; ++c) fill[i * 3 + c] = colour[i * 3 + c] * inv;
}

// … and each finer level: what it sees, and from the level below what it misses (the pull).
__global__ void fill_level_kernel(const float* colour, const float* weight, int w, int h, const float* below, int bw, int bh, float* fill) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  const size_t i = static_cast<size_t>(y) * w + x;
  const float rest = fmaxf(1.0f - weight[i], 0.0f);
  for (int c = 0; c < 3; ++c) fill[i * 3 + c] = colour[i * 3 + c] + resample::pyr_up_at(below, bw, bh, 3, x, y, c) * rest;
}

// ---- Colour --------------------------------------------------------------------------------------

__global__ void colour_kernel(float* img, size_t pixels, CvdTransform t) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= pixels) return;
  float* p = img + i * 3;
  const glm::dvec3 out = cvd_apply(t, glm::dvec3(p[0], p[1], p[2]));
  for (int c = 0; c < 3; ++c) p[c] = static_cast<float>(fmax(0.0, out[c]));
}

}  // namespace

struct ImpairKernels::State {
  // Glare: the coarse grid, the kernel for the media it was made for, the slices' sums
  GlareGrid glare;
  double glare_ppd = -1, eta = 0;
  MediaParams glare_media;
  DeviceArray<float> kernel, small, partial, scattered;
  // Retina
  DeviceArray<glm::vec2> retina;
  DeviceArray<float> gx, gy, source, loss, sensitivity;
  DeviceArray<int> box;
  uint64_t map_of = 0;  // the passes (ImpairmentPasses::id) whose map the device holds
  DeviceArray<float> map;
  DeviceArray<float> levels[9], outputs[9], weights[9];  // a pyramid's levels 1…8 (and filling-in's level 0)
  DeviceArray<double> sums;
  PassEvents events;
};

ImpairKernels::ImpairKernels() : s_(std::make_unique<State>()) {}
ImpairKernels::~ImpairKernels() = default;

ImpairTimes ImpairKernels::apply(const ImpairmentPasses& passes, const CameraRetinotopy& where, float* img, int w, int h) {
  State& s = *s_;
  ImpairTimes t;
  const Impairments& im = passes.impairments();
  if (w <= 0 || h <= 0) return t;
  if (where.width() != w || where.height() != h)
    throw Error("impairments: the retinotopy is of " + std::to_string(where.width()) + "x" + std::to_string(where.height()) +
                ", the image " + std::to_string(w) + "x" + std::to_string(h));
  const RetinotopyGrid grid = where.sizes();
  const size_t pixels = static_cast<size_t>(w) * h;
  const dim3 block(16, 8);
  s.events.record(0);

  // 1. Ocular media
  if (im.media.any()) {
    GlareGrid gg{};
    if (im.media.glare) {
      gg = glare_grid(w, h);
      const double gppd = grid.ppd * gg.columns / w;
      const MediaParams& m = im.media;
      if (gg.columns != s.glare.columns || gg.rows != s.glare.rows || gppd != s.glare_ppd || m.age_years != s.glare_media.age_years ||
          m.pigmentation != s.glare_media.pigmentation || m.cataract != s.glare_media.cataract) {
        s.kernel.upload(glare_grid_kernel(gg, gppd, m, &s.eta));
        s.glare = gg;
        s.glare_ppd = gppd;
        s.glare_media = m;
      }
      const size_t cells = static_cast<size_t>(gg.columns) * gg.rows;
      const int slices = (gg.rows + kSliceRows - 1) / kSliceRows;
      s.small.reserve(cells * 3);
      s.partial.reserve(cells * 3 * slices);
      s.scattered.reserve(cells * 3);
      area_down_kernel<<<grid_for(gg.columns, gg.rows, block), block>>>(img, w, h, s.small.get(), gg.columns, gg.rows);
      FOVEAL_CUDA_LAUNCHED("glare grid");
      const dim3 conv_block(32, 4);
      glare_slice_kernel<<<grid_for(gg.columns, gg.rows, conv_block, slices), conv_block>>>(s.small.get(), gg.columns, gg.rows,
                                                                                            s.kernel.get(), s.partial.get());
      FOVEAL_CUDA_LAUNCHED("glare convolution");
      glare_sum_kernel<<<blocks_for(cells * 3, 256), 256>>>(s.partial.get(), slices, cells * 3, s.scattered.get());
      FOVEAL_CUDA_LAUNCHED("glare sum");
    }
    const glm::dvec3 tr = im.media.yellowing ? lens_transmittance(im.media) : glm::dvec3(1.0);
    media_kernel<<<grid_for(w, h, block), block>>>(img, w, h, s.scattered.get(), gg.columns, gg.rows, static_cast<float>(1.0 - s.eta),
                                                   im.media.glare, im.media.yellowing, glm::vec3(tr));
    FOVEAL_CUDA_LAUNCHED("media");
  }
  s.events.record(1);

  // 2. Retina: metamorphopsia moves the image, the field loss acts where it lands
  if (passes.needs_retinotopy()) s.retina.upload(where.grid().field_deg);  // the fixation's place of every 4th pixel
  if (im.metamorphopsia.any()) {
    const size_t points = static_cast<size_t>(grid.columns) * grid.rows;
    s.gx.reserve(points);
    s.gy.reserve(points);
    s.box.reserve(4);
    const int empty_box[4] = {grid.columns, -1, grid.rows, -1};
    FOVEAL_CUDA_CHECK(cudaMemcpy(s.box.get(), empty_box, sizeof(empty_box), cudaMemcpyHostToDevice));
    distortion_grid_kernel<<<grid_for(grid.columns, grid.rows, block), block>>>(
        s.retina.get(), grid.columns, grid.rows, w, h, im.metamorphopsia.bumps(), grid.ppd, s.gx.get(), s.gy.get(), s.box.get());
    FOVEAL_CUDA_LAUNCHED("distortion grid");
    int box[4];
    FOVEAL_CUDA_CHECK(cudaMemcpy(box, s.box.get(), sizeof(box), cudaMemcpyDeviceToHost));
    if (box[1] >= 0) {  // only the rectangle where something moves (as on the CPU)
      constexpr int step = RetinotopyGrid::kStep;
      const int x0 = std::max(0, (box[0] - 1) * step), y0 = std::max(0, (box[2] - 1) * step);
      const int rw = std::min(w, (box[1] + 1) * step + 1) - x0, rh = std::min(h, (box[3] + 1) * step + 1) - y0;
      s.source.reserve(pixels * 3);
      FOVEAL_CUDA_CHECK(cudaMemcpyAsync(s.source.get(), img, pixels * 3 * sizeof(float), cudaMemcpyDeviceToDevice));
      distort_kernel<<<grid_for(rw, rh, block), block>>>(s.source.get(), img, w, h, s.gx.get(), s.gy.get(), grid.columns, x0, y0, rw, rh);
      FOVEAL_CUDA_LAUNCHED("metamorphopsia");
    }
  }
  if (!passes.field_map().empty()) {
    const FieldMapView host = passes.field_map().view();
    if (passes.id() != s.map_of) {
      s.map.upload(host.loss, static_cast<size_t>(host.n) * host.n);
      s.map_of = passes.id();
    }
    s.loss.reserve(pixels);
    loss_kernel<<<grid_for(w, h, block), block>>>(s.retina.get(), grid.columns, w, h, FieldMapView{s.map.get(), host.n, false},
                                                  s.loss.get());
    FOVEAL_CUDA_LAUNCHED("field loss map");
    const FieldMode mode = im.field_mode;
    const int levels = field_pyramid_levels(w, h);
    int lw[9] = {w}, lh[9] = {h};
    for (int k = 1; k <= levels; ++k) lw[k] = (lw[k - 1] + 1) / 2, lh[k] = (lh[k - 1] + 1) / 2;
    if (mode == FieldMode::contrast || mode == FieldMode::blur) {
      const float* g[9] = {img};
      for (int k = 1; k <= levels; ++k) {
        s.levels[k].reserve(static_cast<size_t>(lw[k]) * lh[k] * 3);
        pyr_down_kernel<<<grid_for(lw[k], lh[k], block), block>>>(g[k - 1], lw[k - 1], lh[k - 1], 3, s.levels[k].get(), lw[k], lh[k]);
        FOVEAL_CUDA_LAUNCHED("field pyramid");
        g[k] = s.levels[k].get();
      }
      const float* below = g[levels];  // the output at the coarsest level is that level itself
      for (int k = levels - 1; k >= 0; --k) {
        float* dst = img;
        if (k > 0) {
          s.outputs[k].reserve(static_cast<size_t>(lw[k]) * lh[k] * 3);
          dst = s.outputs[k].get();
        }
        band_kernel<<<grid_for(lw[k], lh[k], block), block>>>(g[k], lw[k], lh[k], g[k + 1], below, lw[k + 1], lh[k + 1], s.loss.get(), w, h,
                                                              k, mode == FieldMode::contrast, dst);
        FOVEAL_CUDA_LAUNCHED("field band");
        below = dst;
      }
    } else if (mode == FieldMode::grey) {
      s.sensitivity.reserve(pixels);
      sensitivity_kernel<<<blocks_for(pixels, 256), 256>>>(img, s.loss.get(), pixels, s.sensitivity.get(), nullptr);
      FOVEAL_CUDA_LAUNCHED("sensitivity");
      constexpr unsigned kBlocks = 128;
      s.sums.reserve(kBlocks * 3);
      channel_sums_kernel<<<kBlocks, 256>>>(img, pixels, s.sums.get());
      FOVEAL_CUDA_LAUNCHED("image mean");
      std::vector<double> sums(kBlocks * 3);
      s.sums.download(sums.data(), sums.size());
      glm::dvec3 mean(0.0);
      for (unsigned b = 0; b < kBlocks; ++b)
        for (int c = 0; c < 3; ++c) mean[c] += sums[b * 3 + c];
      mean /= static_cast<double>(pixels);
      grey_kernel<<<blocks_for(pixels, 256), 256>>>(img, s.sensitivity.get(), pixels, glm::vec3(mean));
      FOVEAL_CUDA_LAUNCHED("grey");
    } else {  // fill: push the premultiplied colour and the weights down, pull back up
      s.levels[0].reserve(pixels * 3);
      s.weights[0].reserve(pixels);
      sensitivity_kernel<<<blocks_for(pixels, 256), 256>>>(img, s.loss.get(), pixels, s.weights[0].get(), s.levels[0].get());
      FOVEAL_CUDA_LAUNCHED("sensitivity");
      for (int k = 1; k <= levels; ++k) {
        const size_t n = static_cast<size_t>(lw[k]) * lh[k];
        s.levels[k].reserve(n * 3);
        s.weights[k].reserve(n);
        const dim3 gk = grid_for(lw[k], lh[k], block);
        pyr_down_kernel<<<gk, block>>>(s.levels[k - 1].get(), lw[k - 1], lh[k - 1], 3, s.levels[k].get(), lw[k], lh[k]);
        pyr_down_kernel<<<gk, block>>>(s.weights[k - 1].get(), lw[k - 1], lh[k - 1], 1, s.weights[k].get(), lw[k], lh[k]);
        FOVEAL_CUDA_LAUNCHED("filling-in push");
      }
      const size_t top = static_cast<size_t>(lw[levels]) * lh[levels];
      float* fill_top = img;  // no levels: the image is its own coarsest level
      if (levels > 0) {
        s.outputs[levels].reserve(top * 3);
        fill_top = s.outputs[levels].get();
      }
      fill_top_kernel<<<blocks_for(top, 256), 256>>>(s.levels[levels].get(), s.weights[levels].get(), top, fill_top);
      FOVEAL_CUDA_LAUNCHED("filling-in top");
      const float* below = fill_top;
      for (int k = levels - 1; k >= 0; --k) {
        float* dst = img;
        if (k > 0) {
          s.outputs[k].reserve(static_cast<size_t>(lw[k]) * lh[k] * 3);
          dst = s.outputs[k].get();
        }
        fill_level_kernel<<<grid_for(lw[k], lh[k], block), block>>>(s.levels[k].get(), s.weights[k].get(), lw[k], lh[k], below, lw[k + 1],
                                                                    lh[k + 1], dst);
        FOVEAL_CUDA_LAUNCHED("filling-in pull");
        below = dst;
      }
    }
  }
  s.events.record(2);

  // 3. Colour vision
  if (im.cvd.type != CvdType::none) {
    colour_kernel<<<blocks_for(pixels, 256), 256>>>(img, pixels, cvd_transform(im.cvd));
    FOVEAL_CUDA_LAUNCHED("colour");
  }
  s.events.record(3);
  FOVEAL_CUDA_CHECK(cudaDeviceSynchronize());
  t.media_ms = s.events.ms(0, 1);
  t.field_ms = s.events.ms(1, 2);
  t.colour_ms = s.events.ms(2, 3);
  t.total_ms = s.events.ms(0, 3);
  return t;
}

}  // namespace foveal::gpu::detail
