// foveal/cuda/gpu_vision.cu — the vision simulation's passes as kernels over device buffers.
//
// trace → corners → sharpness → blur, as VisionSimulation::step runs them on the CPU, with the
// same per-pixel functions. What differs is only how the work is spread:
// - FAST: one thread per pixel scores it, a second pass keeps the local maxima and appends them
//   to a list with an atomic counter; the list is sorted by row and column on the host, so the
//   corners do not depend on the schedule.
// - The field: pixels share cells, and the CPU updates them in pixel order. A cell's result is
//   the smallest of its pixels' CoCs when that is below the cell's effective CoC, whatever the
//   order; the GPU finds that smallest CoC (and the cell's first pixel, which writes it) with
//   64-bit atomic minima keyed by a per-step serial (ConcurrentFieldUpdate in vision/sharpness.h,
//   held to the pixel-order loop on the CPU), so the scratch arrays never need clearing.
// - The blur: the pyramid, its CoC minima and the tiles are small passes of their own; the gather
//   is one thread per pixel.
#include "foveal/cuda/gpu_internal.cuh"

#include "foveal/util/timer.h"
#include "foveal/vision/blur_kernel.h"
#include "foveal/vision/fast.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace foveal::gpu {
using namespace detail;
namespace {

__global__ void shade_constant_kernel(SceneView scene, const MaterialView* materials, GBufferPtrs g, const Light* lights, int light_count,
                                      float ka, glm::vec3 ambient, float epsilon, int width, int height, glm::vec3* color) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= width || y >= height) return;
  const size_t i = static_cast<size_t>(y) * width + x;
  glm::vec3 c = background_colour();
  if (g.prim[i] != Hit::kNoHit)
    c = shade_point(materials[scene.material_ids[g.prim[i]]], g.albedo[i], g.position[i], g.normal[i], g.geo_normal[i], g.view[i], ka,
                    ambient, lights, light_count, false, epsilon, [](const Ray&) { return false; });
  color[i] = c;
}

// ---- FAST ------------------------------------------------------------------------------------

__global__ void grey_kernel(const glm::vec3* color, const uint8_t* srgb8, size_t pixels, uint8_t* grey) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= pixels) return;
  const glm::vec3 c = color[i];
  grey[i] = fast::grey_of(srgb8[fast::srgb8_index(c.x)], srgb8[fast::srgb8_index(c.y)], srgb8[fast::srgb8_index(c.z)]);
}

__global__ void fast_score_kernel(const uint8_t* grey, int width, int height, int threshold, uint8_t* scores) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= width || y >= height) return;
  scores[static_cast<size_t>(y) * width + x] = static_cast<uint8_t>(fast::score(grey, width, height, x, y, threshold));
}

struct GpuCorner {
  int x, y, score;
};

__global__ void fast_keep_kernel(const uint8_t* scores, int width, int height, bool nonmax, GpuCorner* out, unsigned* count) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= width || y >= height) return;
  const int s = scores[static_cast<size_t>(y) * width + x];
  if (s == 0 || (nonmax && !fast::is_local_maximum(scores, width, height, x, y))) return;
  out[atomicAdd(count, 1U)] = {x, y, s};
}

// ---- Sharpness field -------------------------------------------------------------------------

struct CocArgs {
  CocModel model;
  SharpnessFieldView field;
  const uint32_t* prim;
  const glm::vec3* position;
  const float* depth;
  const glm::vec3* view;
  size_t pixels;
  int64_t* cells;
  float* now_deg;
  glm::vec2* scale;                  // astigmatism, else null
  ConcurrentFieldUpdate concurrent;  // the cells' smallest CoC and first pixel of this step
  bool update;
};

// This step's CoC and cell per pixel; the cells' smallest CoC and first pixel of this step.
__global__ void coc_kernel(CocArgs a) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= a.pixels) return;
  const bool hit = a.prim[i] != Hit::kNoHit;
  const int64_t c = hit ? a.field.cell(a.position[i]) : -1;
  const PixelCoc coc = a.model(hit, a.depth[i], a.view[i]);
  a.cells[i] = c;
  a.now_deg[i] = coc.major_deg;
  if (a.scale) a.scale[i] = coc.scale;
  if (a.update) a.concurrent.offer(c, coc.major_deg, static_cast<uint32_t>(i));
}

// The cell's first pixel applies the cell's smallest CoC, as the CPU's updates in pixel order do.
__global__ void field_update_kernel(CocArgs a, uint32_t step) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= a.pixels) return;
  a.concurrent.apply(a.field, a.cells[i], static_cast<uint32_t>(i), step);
}

// The blur's CoC in pixels: the field's memory where there is geometry, this step's elsewhere.
__global__ void blur_coc_kernel(CocArgs a, uint32_t step, float ppd, float sharp_px, float max_diameter, float* coc_px, float* clamped,
                                unsigned long long* sharp) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= a.pixels) return;
  const int64_t c = a.cells[i];
  const float v = (c >= 0 ? a.field.effective(c, step) : a.now_deg[i]) * ppd;
  coc_px[i] = v;
  clamped[i] = blur::clamp_coc(v, max_diameter);
  if (v < sharp_px) atomicAdd(sharp, 1ULL);
}

// ---- Blur ------------------------------------------------------------------------------------

__global__ void texels_kernel(const glm::vec3* color, size_t pixels, glm::vec4* texels) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= pixels) return;
  const glm::vec3 c = color[i];
  texels[i] = glm::vec4(c, 0.0f);
}

__global__ void box_kernel(const glm::vec4* below, int bw, int bh, glm::vec4* above, int w, int h) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  above[static_cast<size_t>(y) * w + x] = blur::box_average(below, bw, bh, x, y);
}

// Smallest of each 2×2 block of the level below (`halve`), or of each texel's footprint (x, x+1) × (y, y+1)
__global__ void min_kernel(const float* below, int bw, int bh, float* out, int w, int h, bool halve) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= w || y >= h) return;
  out[static_cast<size_t>(y) * w + x] = halve ? blur::min_of_block(below, bw, 2 * x, 2 * y, min(2 * x + 1, bw - 1), min(2 * y + 1, bh - 1))
                                              : blur::min_of_block(below, bw, x, y, min(x + 1, bw - 1), min(y + 1, bh - 1));
}

// One thread per tile: the smallest CoC of its kTile × kTile pixels.
__global__ void tile_min_kernel(const float* clamped, int width, int height, int tiles_x, int tiles_y, float* tile_min) {
  const int tx = blockIdx.x * blockDim.x + threadIdx.x, ty = blockIdx.y * blockDim.y + threadIdx.y;
  if (tx >= tiles_x || ty >= tiles_y) return;
  tile_min[static_cast<size_t>(ty) * tiles_x + tx] = blur::tile_minimum(clamped, width, height, tx, ty);
}

__global__ void gather_kernel(blur::GatherView<glm::vec4> g, const float* image, float* out) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= g.width || y >= g.height) return;
  blur::gather_pixel<3>(g, image, out + (static_cast<size_t>(y) * g.width + x) * 3, x, y);
}

}  // namespace

struct VisionPasses::Impl {
  Renderer renderer;  // the scene on the GPU and the G-buffer
  BlurParams blur_params;
  VisionPassTimes times;
  PassEvents events;
  int width = 0, height = 0;
  bool traced = false, cocs_ready = false, astigmatic = false;

  // Image and FAST
  DeviceArray<glm::vec3> perceived;
  DeviceArray<uint8_t> srgb8, grey, scores;
  DeviceArray<GpuCorner> corner_list;
  DeviceArray<unsigned> corner_count;
  DeviceArray<MaterialView> materials;

  // Field
  SharpnessFieldView field;  // pointers into the arrays below
  DeviceArray<float> field_coc, growth;
  DeviceArray<uint32_t> field_stamp, field_written;
  DeviceArray<unsigned long long> cell_min, cell_owner;
  uint32_t serial = 0;
  DeviceArray<int64_t> cells;
  DeviceArray<float> now_deg, coc_px;
  DeviceArray<glm::vec2> scale;
  DeviceArray<unsigned long long> sharp_count;

  // Blur
  blur::GatherView<glm::vec4> gather;
  DeviceArray<glm::vec2> tap_offsets;
  DeviceArray<float> tap_weights;
  DeviceArray<int> tap_start;
  DeviceArray<glm::vec4> level_texels[blur::kMaxLevels];
  DeviceArray<float> level_min[blur::kMaxLevels], level_quad[blur::kMaxLevels];
  DeviceArray<float> clamped, tile_min;

  // An impaired eye's passes (cuda/gpu_impair.cu)
  ImpairKernels impair;

  Renderer::Impl* rimpl = nullptr;  // the renderer's buffers (set by VisionPasses, its friend)

  explicit Impl(const Scene& scene) : renderer(scene) {}
  Renderer::Impl& r() const { return *rimpl; }
};

VisionPasses::VisionPasses(const Scene& scene, const SharpnessField& field, const BlurParams& blur) {
  impl_ = std::make_unique<Impl>(scene);  // throws with the reason when no GPU answers
  Impl& m = *impl_;
  m.rimpl = m.renderer.impl_.get();
  m.blur_params = blur;
  m.srgb8.upload(srgb8_table());
  m.materials.upload(material_views(scene));
  // An empty field with the CPU's grid and growth table
  const SharpnessFieldView& cpu = field.view();
  const size_t cells = field.cells();
  m.field_coc.reserve(cells);
  m.field_stamp.reserve(cells);
  m.field_written.reserve(cells);
  m.cell_min.reserve(cells);
  m.cell_owner.reserve(cells);
  std::vector<float> unseen(cells, SharpnessField::kUnseen);
  m.field_coc.upload(unseen);
  FOVEAL_CUDA_CHECK(cudaMemset(m.field_stamp.get(), 0, cells * sizeof(uint32_t)));
  FOVEAL_CUDA_CHECK(cudaMemset(m.field_written.get(), 0, cells * sizeof(uint32_t)));
  // All ones: serial 0 in the high word, older than every step's
  FOVEAL_CUDA_CHECK(cudaMemset(m.cell_min.get(), 0xff, cells * sizeof(unsigned long long)));
  FOVEAL_CUDA_CHECK(cudaMemset(m.cell_owner.get(), 0xff, cells * sizeof(unsigned long long)));
  m.growth.upload(field.growth_table());
  m.field = cpu;
  m.field.coc = m.field_coc.get();
  m.field.stamp = m.field_stamp.get();
  m.field.written = m.field_written.get();
  m.field.growth = m.growth.get();
  m.field.epoch = 1;
  m.sharp_count.reserve(1);
  m.corner_count.reserve(1);
  // The blur's tap patterns
  const TapTable taps = make_tap_table(blur.taps);
  m.tap_offsets.upload(taps.offsets);
  m.tap_weights.upload(taps.weights);
  m.tap_start.upload(taps.start);
  m.gather.offsets = m.tap_offsets.get();
  m.gather.weights = m.tap_weights.get();
  m.gather.pattern_start = m.tap_start.get();
  m.gather.first_count = taps.first_count;
  m.gather.max_taps = taps.max_taps;
  m.gather.scatter_aware = blur.scatter_aware;
}

VisionPasses::~VisionPasses() = default;

void VisionPasses::trace(const Camera& camera, int w, int h, float ambient) {
  Impl& m = *impl_;
  Renderer::Impl& r = m.r();
  const size_t n = static_cast<size_t>(w) * h;
  for (auto* a : {&r.position, &r.geo_normal, &r.normal, &r.albedo, &r.view, &r.color, &m.perceived}) a->reserve(n);
  r.depth.reserve(n);
  r.prim.reserve(n);
  m.width = w;
  m.height = h;
  const std::vector<Light> lights = frame_lights(r.scene_lights, camera);
  r.lights.upload(lights);
  const GBufferPtrs g{r.prim.get(), r.position.get(), r.geo_normal.get(), r.normal.get(), r.albedo.get(), r.view.get(), r.depth.get()};
  const dim3 block(16, 8), grid = grid_for(w, h, block);
  m.events.record(0);
  primary_kernel<<<grid, block>>>(r.bvh_view(), r.scene_view(), CameraRays(camera, w, h), w, h, g);
  FOVEAL_CUDA_LAUNCHED("primary rays");
  shade_constant_kernel<<<grid, block>>>(r.scene_view(), m.materials.get(), g, r.lights.get(), static_cast<int>(lights.size()), ambient,
                                         r.ambient, r.epsilon, w, h, r.color.get());
  FOVEAL_CUDA_LAUNCHED("shading");
  m.events.record(1);
  FOVEAL_CUDA_CHECK(cudaEventSynchronize(m.events.e[1]));
  FOVEAL_CUDA_CHECK(cudaGetLastError());
  m.times = {};
  m.times.trace_ms = m.events.ms(0, 1);
  m.traced = true;
  m.cocs_ready = false;
}

std::vector<Corner> VisionPasses::corners(int threshold, bool nonmax) {
  Impl& m = *impl_;
  if (!m.traced) throw Error("gpu::VisionPasses::corners before trace");
  const int w = m.width, h = m.height;
  const size_t n = static_cast<size_t>(w) * h;
  m.grey.reserve(n);
  m.scores.reserve(n);
  m.corner_list.reserve(n);
  const dim3 block(16, 8), grid = grid_for(w, h, block);
  m.events.record(0);
  FOVEAL_CUDA_CHECK(cudaMemset(m.corner_count.get(), 0, sizeof(unsigned)));
  grey_kernel<<<blocks_for(n, 256), 256>>>(m.r().color.get(), m.srgb8.get(), n, m.grey.get());
  FOVEAL_CUDA_LAUNCHED("grey");
  fast_score_kernel<<<grid, block>>>(m.grey.get(), w, h, threshold, m.scores.get());
  FOVEAL_CUDA_LAUNCHED("FAST scores");
  fast_keep_kernel<<<grid, block>>>(m.scores.get(), w, h, nonmax, m.corner_list.get(), m.corner_count.get());
  FOVEAL_CUDA_LAUNCHED("FAST suppression");
  unsigned count = 0;
  m.corner_count.download(&count, 1);
  std::vector<GpuCorner> found(count);
  m.corner_list.download(found.data(), count);
  m.events.record(1);
  FOVEAL_CUDA_CHECK(cudaEventSynchronize(m.events.e[1]));
  m.times.features_ms = m.events.ms(0, 1);
  std::sort(found.begin(), found.end(), [](const GpuCorner& a, const GpuCorner& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  std::vector<Corner> out;
  out.reserve(found.size());
  for (const GpuCorner& c : found) out.push_back({{c.x + 0.5f, c.y + 0.5f}, static_cast<float>(c.score)});
  return out;
}

float VisionPasses::depth_at(int x, int y, glm::vec3* view) {
  Impl& m = *impl_;
  if (!m.traced || x < 0 || y < 0 || x >= m.width || y >= m.height) throw Error("gpu::VisionPasses::depth_at: no such pixel");
  const size_t i = static_cast<size_t>(y) * m.width + x;
  float depth = 0;
  FOVEAL_CUDA_CHECK(cudaMemcpy(&depth, m.r().depth.get() + i, sizeof depth, cudaMemcpyDeviceToHost));
  if (view) FOVEAL_CUDA_CHECK(cudaMemcpy(view, m.r().view.get() + i, sizeof *view, cudaMemcpyDeviceToHost));
  return depth;
}

void VisionPasses::blink() { ++impl_->field.epoch; }

size_t VisionPasses::sharpness(const CocModel& model, uint32_t step, bool update, float ppd, float sharp_px) {
  Impl& m = *impl_;
  if (!m.traced) throw Error("gpu::VisionPasses::sharpness before trace");
  Renderer::Impl& r = m.r();
  const size_t n = static_cast<size_t>(m.width) * m.height;
  m.cells.reserve(n);
  m.now_deg.reserve(n);
  m.coc_px.reserve(n);
  m.clamped.reserve(n);
  m.astigmatic = model.astigmatic;
  if (m.astigmatic) m.scale.reserve(n);
  if (update) ++m.serial;
  const CocArgs a{model,
                  m.field,
                  r.prim.get(),
                  r.position.get(),
                  r.depth.get(),
                  r.view.get(),
                  n,
                  m.cells.get(),
                  m.now_deg.get(),
                  m.astigmatic ? m.scale.get() : nullptr,
                  ConcurrentFieldUpdate{m.cell_min.get(), m.cell_owner.get(), m.serial},
                  update};
  m.events.record(0);
  FOVEAL_CUDA_CHECK(cudaMemset(m.sharp_count.get(), 0, sizeof(unsigned long long)));
  coc_kernel<<<blocks_for(n, 256), 256>>>(a);
  FOVEAL_CUDA_LAUNCHED("circles of confusion");
  if (update) {
    field_update_kernel<<<blocks_for(n, 256), 256>>>(a, step);
    FOVEAL_CUDA_LAUNCHED("sharpness field");
  }
  blur_coc_kernel<<<blocks_for(n, 256), 256>>>(a, step, ppd, sharp_px, m.blur_params.max_diameter_px, m.coc_px.get(), m.clamped.get(),
                                               m.sharp_count.get());
  FOVEAL_CUDA_LAUNCHED("blur CoC");
  unsigned long long sharp = 0;
  m.sharp_count.download(&sharp, 1);
  m.events.record(1);
  FOVEAL_CUDA_CHECK(cudaEventSynchronize(m.events.e[1]));
  m.times.sharpness_ms = m.events.ms(0, 1);
  m.cocs_ready = true;
  return static_cast<size_t>(sharp);
}

void VisionPasses::blur(float axis_deg) {
  Impl& m = *impl_;
  if (!m.cocs_ready) throw Error("gpu::VisionPasses::blur before sharpness");
  const int w = m.width, h = m.height;
  const size_t n = static_cast<size_t>(w) * h;
  blur::GatherView<glm::vec4>& g = m.gather;
  g.width = w;
  g.height = h;
  g.coc = m.clamped.get();
  g.shape = m.astigmatic ? m.scale.get() : nullptr;
  g.along = glm::vec2(1, 0);
  g.across = glm::vec2(0, 1);
  if (m.astigmatic) ellipse_axes(axis_deg, &g.along, &g.across);
  const dim3 block(16, 8);
  m.events.record(0);
  // The pyramid of the image and of the CoCs' minima, as blur.cpp builds it
  int lw = w, lh = h;
  g.level_count = 0;
  for (int l = 0; l < blur::kMaxLevels; ++l) {
    if (l > 0 && !blur::next_level(&lw, &lh)) break;
    const size_t texels = static_cast<size_t>(lw) * lh;
    m.level_texels[l].reserve(texels);
    m.level_min[l].reserve(texels);
    m.level_quad[l].reserve(texels);
    const dim3 grid = grid_for(lw, lh, block);
    if (l == 0) {
      texels_kernel<<<blocks_for(n, 256), 256>>>(m.r().color.get(), n, m.level_texels[0].get());
      FOVEAL_CUDA_CHECK(cudaMemcpyAsync(m.level_min[0].get(), m.clamped.get(), n * sizeof(float), cudaMemcpyDeviceToDevice));
    } else {
      const int bw = g.levels[l - 1].width, bh = g.levels[l - 1].height;
      box_kernel<<<grid, block>>>(m.level_texels[l - 1].get(), bw, bh, m.level_texels[l].get(), lw, lh);
      min_kernel<<<grid, block>>>(m.level_min[l - 1].get(), bw, bh, m.level_min[l].get(), lw, lh, true);
    }
    FOVEAL_CUDA_LAUNCHED("blur pyramid");
    min_kernel<<<grid, block>>>(m.level_min[l].get(), lw, lh, m.level_quad[l].get(), lw, lh, false);
    FOVEAL_CUDA_LAUNCHED("blur footprint minima");
    g.levels[l] = {lw, lh, m.level_texels[l].get(), m.level_quad[l].get()};
    g.level_count = l + 1;
  }
  g.tiles_x = (w + blur::kTile - 1) / blur::kTile;
  g.tiles_y = (h + blur::kTile - 1) / blur::kTile;
  m.tile_min.reserve(static_cast<size_t>(g.tiles_x) * g.tiles_y);
  g.tile_min = m.tile_min.get();
  tile_min_kernel<<<grid_for(g.tiles_x, g.tiles_y, dim3(16, 16)), dim3(16, 16)>>>(m.clamped.get(), w, h, g.tiles_x, g.tiles_y,
                                                                                  m.tile_min.get());
  FOVEAL_CUDA_LAUNCHED("blur tiles");
  gather_kernel<<<grid_for(w, h, block), block>>>(g, reinterpret_cast<const float*>(m.r().color.get()),
                                                  reinterpret_cast<float*>(m.perceived.get()));
  FOVEAL_CUDA_LAUNCHED("blur gather");
  m.events.record(1);
  FOVEAL_CUDA_CHECK(cudaEventSynchronize(m.events.e[1]));
  FOVEAL_CUDA_CHECK(cudaGetLastError());
  m.times.blur_ms = m.events.ms(0, 1);
}

namespace {

Image download_image(const DeviceArray<glm::vec3>& buffer, int w, int h) {
  Image img(w, h, 3);
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
  buffer.download(reinterpret_cast<glm::vec3*>(img.pixels.data()), static_cast<size_t>(w) * h);
  return img;
}

}  // namespace

Image VisionPasses::color() const {
  const Timer t;
  Image img = download_image(impl_->r().color, impl_->width, impl_->height);
  impl_->times.download_ms += t.ms();
  return img;
}

ImpairTimes VisionPasses::impair(const ImpairmentPasses& passes, const CameraRetinotopy& where) {
  Impl& m = *impl_;
  if (!m.traced) throw Error("gpu::VisionPasses::impair before trace");
  return m.impair.apply(passes, where, reinterpret_cast<float*>(m.perceived.get()), m.width, m.height);
}

Image VisionPasses::perceived() const {
  const Timer t;
  Image img = download_image(impl_->perceived, impl_->width, impl_->height);
  impl_->times.download_ms += t.ms();
  return img;
}

std::vector<float> VisionPasses::coc_px() const {
  std::vector<float> out(static_cast<size_t>(impl_->width) * impl_->height);
  impl_->coc_px.download(out.data(), out.size());
  return out;
}

const VisionPassTimes& VisionPasses::last_times() const { return impl_->times; }

}  // namespace foveal::gpu
