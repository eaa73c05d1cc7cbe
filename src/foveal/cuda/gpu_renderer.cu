// foveal/cuda/gpu_renderer.cu — the GPU renderer: one kernel per pass over device buffers.
#include "foveal/cuda/gpu_internal.cuh"

#include "foveal/util/error.h"
#include "foveal/util/sampling.h"
#include "foveal/util/timer.h"

#include <cub/device/device_scan.cuh>
#include <cuda_runtime.h>
#include <tbb/parallel_for.h>

#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace foveal::gpu {
using namespace detail;
namespace {

// ---- Kernels ---------------------------------------------------------------------------------

struct MapPtrs {
  float* quality;
  float* eccentricity;
  uint16_t* rays;
  float* blend;
  unsigned long long* ray_count;  // rays the AO pass traces for the pixel (0 where nothing was hit)
};

__global__ void foveation_kernel(FoveationModel model, bool foveated, int max_rays, int width, int height, const uint32_t* prim, MapPtrs m,
                                 FrameCounters* counters) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= width || y >= height) return;
  const size_t i = static_cast<size_t>(y) * width + x;
  const FoveaSample s = model.evaluate(x, y);
  m.eccentricity[i] = static_cast<float>(s.effective_deg);
  float q = 1.0f, b = max_rays > 0 ? 1.0f : 0.0f;
  int n = max_rays;
  if (foveated) {
    q = static_cast<float>(s.quality);
    n = s.rays;
    b = static_cast<float>(s.blend);
  }
  m.quality[i] = q;
  m.rays[i] = static_cast<uint16_t>(n);
  m.blend[i] = b;
  const bool hit = prim[i] != Hit::kNoHit;
  m.ray_count[i] = hit ? static_cast<unsigned long long>(n) : 0ULL;
  if (hit) {
    atomicMin(&counters->min_rays, n);
    atomicMax(&counters->max_rays, n);
  }
}

struct AoArgs {
  BvhView bvh;
  const glm::vec3* position;
  const glm::vec3* geo_normal;
  const unsigned long long* offset;  // exclusive prefix sum of ray_count
  const unsigned long long* ray_count;
  const uint32_t* sobol;
  uint32_t* blocked;  // per pixel, zeroed before the pass
  const FrameCounters* counters;
  size_t pixels;
  int width;
  float ao_distance, epsilon;
  uint64_t seed;
};

__device__ AoPixelRays pixel_rays(const AoArgs& a, size_t i) {
  return AoPixelRays(a.position[i], a.geo_normal[i], a.epsilon, a.ao_distance, a.seed, static_cast<uint32_t>(i % a.width),
                     static_cast<uint32_t>(i / a.width), a.sobol);
}

// Balanced: the frame's rays in pixel order, kAoChunk consecutive rays per thread (gpu_internal.cuh),
// a grid-stride loop over chunks. A thread finds its first pixel by binary search in the prefix
// sum (holder_of), then walks on; blocked counts are integers added atomically, so the result is
// exact in any order.
// The real-time loop's AO tasks go in launches of about this many rays (0.2–0.5 ms on an H100), each
// a point where a batch stops at its deadline
constexpr unsigned long long kTaskLaunchRays = 1ULL << 21;

__global__ void ao_balanced_kernel(AoArgs a) {
  const unsigned long long total = a.counters->total_rays;
  const unsigned long long chunks = (total + detail::kAoChunk - 1) / detail::kAoChunk;
  for (unsigned long long c = blockIdx.x * static_cast<unsigned long long>(blockDim.x) + threadIdx.x; c < chunks;
       c += static_cast<unsigned long long>(gridDim.x) * blockDim.x) {
    unsigned long long r = c * detail::kAoChunk;
    const unsigned long long end = min(r + detail::kAoChunk, total);
    size_t pixel = detail::holder_of(a.offset, 0, a.pixels, r);
    unsigned long long pixel_end = a.offset[pixel] + a.ray_count[pixel];
    AoPixelRays rays = pixel_rays(a, pixel);
    uint32_t blocked = 0;
    for (; r < end; ++r) {
      if (r >= pixel_end) {
        if (blocked) atomicAdd(&a.blocked[pixel], blocked);
        blocked = 0;
        do ++pixel;
        while (a.ray_count[pixel] == 0);
        pixel_end = a.offset[pixel] + a.ray_count[pixel];
        rays = pixel_rays(a, pixel);
      }
      const Ray ray = rays(static_cast<uint32_t>(r - a.offset[pixel]));
      blocked += bvh_trace<true>(a.bvh, ray, nullptr) ? 1U : 0U;
    }
    if (blocked) atomicAdd(&a.blocked[pixel], blocked);
  }
}

// Per pixel: one thread loops over its own pixel's rays (as the papers' OptiX kernels did).
__global__ void ao_per_pixel_kernel(AoArgs a) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= a.pixels) return;
  const auto n = static_cast<uint32_t>(a.ray_count[i]);
  if (n == 0) return;
  const AoPixelRays rays = pixel_rays(a, i);
  uint32_t blocked = 0;
  for (uint32_t k = 0; k < n; ++k) blocked += bvh_trace<true>(a.bvh, rays(k), nullptr) ? 1U : 0U;
  a.blocked[i] = blocked;
}

// AO tasks (the real-time loop's rays), balanced as a frame's: one launch's rays laid end to end
// by the tasks' prefix sum (made on the host; a task off the surfaces has none), kAoChunk
// consecutive rays per thread, so a fovea's few thousand tasks of hundreds of rays each spread
// over the whole GPU instead of a few thousand threads. Blocked counts are integers added
// atomically: exact in any order.
struct AoTaskArgs {
  BvhView bvh;
  const glm::vec3* position;
  const glm::vec3* geo_normal;
  const AoRayTask* tasks;
  const unsigned long long* offset;  // per task, the first of its rays; offset[count] = all rays
  uint32_t* blocked;                 // per task, zeroed before the launch
  const uint32_t* sobol;
  size_t first_task, end_task;  // this launch's tasks, and their rays [offset[first], offset[end])
  int width;
  float ao_distance, epsilon;
  uint64_t seed;
};

__device__ AoPixelRays task_rays(const AoTaskArgs& a, uint32_t pixel) {
  return AoPixelRays(a.position[pixel], a.geo_normal[pixel], a.epsilon, a.ao_distance, a.seed, pixel % static_cast<uint32_t>(a.width),
                     pixel / static_cast<uint32_t>(a.width), a.sobol);
}

__global__ void ao_tasks_kernel(AoTaskArgs a) {
  const unsigned long long begin = a.offset[a.first_task], total = a.offset[a.end_task];
  const unsigned long long chunks = (total - begin + detail::kAoChunk - 1) / detail::kAoChunk;
  for (unsigned long long c = blockIdx.x * static_cast<unsigned long long>(blockDim.x) + threadIdx.x; c < chunks;
       c += static_cast<unsigned long long>(gridDim.x) * blockDim.x) {
    unsigned long long r = begin + c * detail::kAoChunk;
    const unsigned long long end = min(r + detail::kAoChunk, total);
    size_t t = detail::holder_of(a.offset, a.first_task, a.end_task, r);
    AoPixelRays rays = task_rays(a, a.tasks[t].pixel);
    uint32_t blocked = 0;
    for (; r < end; ++r) {
      if (r >= a.offset[t + 1]) {
        if (blocked) atomicAdd(&a.blocked[t], blocked);
        blocked = 0;
        do ++t;
        while (a.offset[t + 1] == a.offset[t]);
        rays = task_rays(a, a.tasks[t].pixel);
      }
      const Ray ray = rays(a.tasks[t].first + static_cast<uint32_t>(r - a.offset[t]));
      blocked += bvh_trace<true>(a.bvh, ray, nullptr) ? 1U : 0U;
    }
    if (blocked) atomicAdd(&a.blocked[t], blocked);
  }
}

// Per-pixel AO visibility V = open / n, and the fovea's sums for the `auto` ambient constant.
__global__ void visibility_kernel(size_t pixels, const unsigned long long* ray_count, const float* quality, const uint32_t* blocked,
                                  float* visibility, FrameCounters* counters) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= pixels) return;
  const auto n = static_cast<uint32_t>(ray_count[i]);
  const uint32_t open = n - blocked[i];
  visibility[i] = n > 0 ? static_cast<float>(open) / static_cast<float>(n) : 1.0f;
  if (n > 0 && quality[i] >= 1.0f) {
    atomicAdd(&counters->fovea_open, static_cast<unsigned long long>(open));
    atomicAdd(&counters->fovea_pixels, 1ULL);
  }
}

struct ShadeArgs {
  BvhView bvh;
  const uint32_t* prim;
  const uint32_t* material_ids;
  const MaterialView* materials;
  GBufferPtrs g;
  const float* blend;
  const float* visibility;
  const Light* lights;
  int light_count;
  glm::vec3 ambient;
  bool auto_constant;
  bool reused;             // quality per ray: the `auto` constant from the fovea's Σ V
  float ambient_constant;  // when not auto
  int max_rays;
  bool shadows;
  float epsilon;
  int width, height;
  glm::vec3* color;
  FrameCounters* counters;
};

__global__ void shade_kernel(ShadeArgs a) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= a.width || y >= a.height) return;
  const size_t i = static_cast<size_t>(y) * a.width + x;
  glm::vec3 c = background_colour();
  if (a.prim[i] != Hit::kNoHit) {
    const float k_const = !a.auto_constant ? a.ambient_constant
                          : a.reused       ? fovea_mean_reused_visibility(*a.counters)
                                           : fovea_mean_visibility(*a.counters, a.max_rays);
    const float b = a.blend[i];
    const float ka = b * a.visibility[i] + (1.0f - b) * k_const;
    uint32_t shadow_rays = 0;
    c = shade_point(a.materials[a.material_ids[a.prim[i]]], a.g.albedo[i], a.g.position[i], a.g.normal[i], a.g.geo_normal[i], a.g.view[i],
                    ka, a.ambient, a.lights, a.light_count, a.shadows, a.epsilon, [&](const Ray& ray) {
                      ++shadow_rays;
                      return bvh_trace<true>(a.bvh, ray, nullptr);
                    });
    if (shadow_rays) atomicAdd(&a.counters->shadow_rays, static_cast<unsigned long long>(shadow_rays));
  }
  a.color[i] = c;
}

__global__ void intersect_kernel(BvhView bvh, const Ray* rays, Hit* hits, size_t count) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= count) return;
  Hit h;
  bvh_trace<false>(bvh, rays[i], &h);
  hits[i] = h;
}

__global__ void occluded_kernel(BvhView bvh, const Ray* rays, uint8_t* occluded, size_t count) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (i >= count) return;
  occluded[i] = bvh_trace<true>(bvh, rays[i], nullptr) ? 1 : 0;
}

__global__ void total_kernel(const unsigned long long* offset, const unsigned long long* ray_count, size_t pixels,
                             FrameCounters* counters) {
  counters->total_rays = pixels > 0 ? offset[pixels - 1] + ray_count[pixels - 1] : 0ULL;
}

}  // namespace

}  // namespace foveal::gpu

// ---- Availability (util/device.h) ---------------------------------------------------------

namespace foveal {

const Availability& availability() {
  static const Availability found = [] {
    Availability a;
    a.compiled = true;
    // The runtime would report a missing driver as "insufficient"; say what is missing
    void* driver = dlopen("libcuda.so.1", RTLD_LAZY | RTLD_LOCAL);
    if (driver == nullptr) {
      a.reason = "no NVIDIA driver is installed (libcuda.so.1 cannot be loaded)";
      return a;
    }
    dlclose(driver);
    int count = 0;
    const cudaError_t status = cudaGetDeviceCount(&count);
    if (status != cudaSuccess) {
      a.reason = std::string("the CUDA runtime found no usable GPU: ") + cudaGetErrorString(status);
      cudaGetLastError();
      return a;
    }
    if (count == 0) {
      a.reason = "no CUDA-capable GPU is present";
      return a;
    }
    cudaDeviceProp prop{};
    if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess) {
      a.reason = "cannot read the GPU's properties";
      return a;
    }
    a.name = prop.name;
    a.compute_major = prop.major;
    a.compute_minor = prop.minor;
    a.multiprocessors = prop.multiProcessorCount;
    a.memory_gib = static_cast<double>(prop.totalGlobalMem) / (1024.0 * 1024.0 * 1024.0);
    // A trivial allocation proves the context starts (and that this build has code for the GPU)
    void* probe = nullptr;
    const cudaError_t alloc = cudaMalloc(&probe, 256);
    if (alloc != cudaSuccess) {
      a.reason = std::string("the GPU cannot be used: ") + cudaGetErrorString(alloc);
      cudaGetLastError();
      return a;
    }
    cudaFree(probe);
    a.usable = true;
    return a;
  }();
  return found;
}

std::string Availability::describe() const {
  if (!usable) return reason;
  char text[256];
  std::snprintf(text, sizeof text, "%s (compute %d.%d, %d SMs, %.1f GiB)", name.c_str(), compute_major, compute_minor, multiprocessors,
                memory_gib);
  return text;
}

}  // namespace foveal

namespace foveal::gpu {

// ---- Renderer --------------------------------------------------------------------------------

const char* to_string(AoSchedule schedule) { return schedule == AoSchedule::balanced ? "balanced" : "per-pixel"; }

Renderer::Renderer(const Scene& scene) {
  const Availability& a = availability();
  if (!a.usable) throw Error("device cuda: " + a.reason);
  impl_ = std::make_unique<Impl>();  // CUDA events and buffers: only once a GPU answered
  Impl& m = *impl_;
  m.bvh = build_bvh(scene);
  m.triangle_count = scene.triangles.size();
  m.nodes.upload(m.bvh.nodes);
  m.triangles.upload(m.bvh.triangles);
  m.positions.upload(scene.positions);
  m.normals.upload(scene.normals);
  m.uvs.upload(scene.uvs);
  m.tris.upload(scene.triangles);
  m.material_ids.upload(scene.material_ids);
  // Textures: one buffer of texels, views pointing into it
  size_t texel_bytes = 0;
  for (const Texture& t : scene.textures) texel_bytes += t.rgb.size();
  std::vector<uint8_t> texels;
  texels.reserve(texel_bytes);
  std::vector<size_t> starts;
  for (const Texture& t : scene.textures) {
    starts.push_back(texels.size());
    texels.insert(texels.end(), t.rgb.begin(), t.rgb.end());
  }
  m.texels.upload(texels);
  std::vector<TextureView> views;
  for (size_t k = 0; k < scene.textures.size(); ++k)
    views.push_back({m.texels.get() + starts[k], scene.textures[k].width, scene.textures[k].height});
  m.textures.upload(views);
  m.materials.upload(material_views(scene));
  m.srgb_lut.upload(srgb_to_linear_lut(), 256);
  m.sobol.upload(sobol_table_2d(), 2 * kSobolTableSize);
  m.ambient = scene.ambient;
  m.scene_lights = scene.lights;
  const Bounds bounds = scene.bounds();
  m.epsilon = surface_epsilon(bounds);
  m.default_ao_distance = resolve_ao_distance(scene, bounds, std::nullopt);
  m.counters.reserve(1);
  // A grid that fills the GPU for the balanced AO kernel's grid-stride loop
  int per_sm = 0;
  FOVEAL_CUDA_CHECK(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, ao_balanced_kernel, 128, 0));
  m.ao_grid = std::max(1, per_sm) * a.multiprocessors;
}

Renderer::~Renderer() = default;

void Renderer::set_ao_schedule(AoSchedule schedule) { impl_->schedule = schedule; }
void Renderer::reset_history() { impl_->history.frames = 0; }
uint32_t Renderer::history_frames() const { return impl_->history.frames; }
AoSchedule Renderer::ao_schedule() const { return impl_->schedule; }
const Bvh& Renderer::bvh() const { return impl_->bvh; }
const GpuPassTimes& Renderer::last_times() const { return impl_->times; }

Frame Renderer::render(const Camera& camera, const RenderParams& params, const FrameOutputs& outputs) {
  validate(params);
  Impl& m = *impl_;
  const int w = params.width, h = params.height;
  const size_t n = static_cast<size_t>(w) * h;
  for (auto* a : {&m.position, &m.geo_normal, &m.normal, &m.albedo, &m.view, &m.color}) a->reserve(n);
  for (auto* a : {&m.depth, &m.quality, &m.eccentricity, &m.blend, &m.visibility}) a->reserve(n);
  m.prim.reserve(n);
  m.rays.reserve(n);
  m.ray_count.reserve(n);
  m.offset.reserve(n);
  m.blocked.reserve(n);
  size_t temp_bytes = 0;
  FOVEAL_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, temp_bytes, m.ray_count.get(), m.offset.get(), n));
  if (temp_bytes > m.scan_temp_bytes) {
    m.scan_temp.reserve(temp_bytes);
    m.scan_temp_bytes = temp_bytes;
  }
  const std::vector<Light> lights = frame_lights(m.scene_lights, camera);
  m.lights.upload(lights);
  Frame f;
  f.gaze_px = params.gaze_px.value_or(glm::dvec2(w * 0.5, h * 0.5));
  const float ao_distance = params.ao_distance ? *params.ao_distance : m.default_ao_distance;
  const FoveationModel model(params.display, w, h, f.gaze_px, params.foveation);
  FrameCounters zero{0, 0, 0, 0, std::numeric_limits<int>::max(), 0};
  FOVEAL_CUDA_CHECK(cudaMemcpy(m.counters.get(), &zero, sizeof zero, cudaMemcpyHostToDevice));
  FOVEAL_CUDA_CHECK(cudaMemset(m.blocked.get(), 0, n * sizeof(uint32_t)));
  const dim3 block2d(16, 8), grid2d((w + 15) / 16, (h + 7) / 8);
  const GBufferPtrs g{m.prim.get(), m.position.get(), m.geo_normal.get(), m.normal.get(), m.albedo.get(), m.view.get(), m.depth.get()};
  PassEvents& ev = m.events;
  ev.record(0);
  // Primary rays → G-buffer
  primary_kernel<<<grid2d, block2d>>>(m.bvh_view(), m.scene_view(), CameraRays(camera, w, h), w, h, g);
  FOVEAL_CUDA_LAUNCHED("primary rays");
  ev.record(1);
  // Foveation model → q, n, b and each pixel's ray count
  const MapPtrs maps{m.quality.get(), m.eccentricity.get(), m.rays.get(), m.blend.get(), m.ray_count.get()};
  foveation_kernel<<<grid2d, block2d>>>(model, params.mode == RenderMode::foveated, params.foveation.max_rays, w, h, m.prim.get(), maps,
                                        m.counters.get());
  FOVEAL_CUDA_LAUNCHED("foveation model");
  ev.record(2);
  const bool reuse = params.reuse.any();
  float* visibility = m.visibility.get();
  int last = 5;  // the event after shading
  if (!reuse) {
    // Prefix sum of the ray counts; the total goes straight into the counters
    temp_bytes = m.scan_temp_bytes;
    FOVEAL_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(m.scan_temp.get(), temp_bytes, m.ray_count.get(), m.offset.get(), n));
    total_kernel<<<1, 1>>>(m.offset.get(), m.ray_count.get(), n, m.counters.get());
    FOVEAL_CUDA_LAUNCHED("ray total");
    ev.record(3);
    // Foveated AO
    AoArgs ao{m.bvh_view(),
              m.position.get(),
              m.geo_normal.get(),
              m.offset.get(),
              m.ray_count.get(),
              m.sobol.get(),
              m.blocked.get(),
              m.counters.get(),
              n,
              w,
              ao_distance,
              m.epsilon,
              params.seed};
    if (m.schedule == AoSchedule::balanced)
      ao_balanced_kernel<<<m.ao_grid, 128>>>(ao);
    else
      ao_per_pixel_kernel<<<blocks_for(n, 128), 128>>>(ao);
    FOVEAL_CUDA_LAUNCHED("ambient occlusion");
    ev.record(4);
    visibility_kernel<<<blocks_for(n, 256), 256>>>(n, m.ray_count.get(), m.quality.get(), m.blocked.get(), m.visibility.get(),
                                                   m.counters.get());
    FOVEAL_CUDA_LAUNCHED("visibility");
  } else {
    // Quality per ray: history, adaptive rounds, the filter (events 3, 4 and 5)
    visibility = run_reuse_passes(m, {&camera, &params, ao_distance, n});
    last = 6;
  }
  // Phong shading with the blended ambient term
  ShadeArgs sh{m.bvh_view(),
               m.prim.get(),
               m.material_ids.get(),
               m.materials.get(),
               g,
               m.blend.get(),
               visibility,
               m.lights.get(),
               static_cast<int>(lights.size()),
               m.ambient,
               !params.ambient_constant.has_value(),
               reuse,
               params.ambient_constant.value_or(1.0f),
               params.foveation.max_rays,
               params.shadows,
               m.epsilon,
               w,
               h,
               m.color.get(),
               m.counters.get()};
  shade_kernel<<<grid2d, block2d>>>(sh);
  FOVEAL_CUDA_LAUNCHED("shading");
  ev.record(last);
  FOVEAL_CUDA_CHECK(cudaEventSynchronize(ev.e[last]));
  FOVEAL_CUDA_CHECK(cudaGetLastError());  // a fault inside a kernel
  m.times.primary_ms = ev.ms(0, 1);
  m.times.foveation_ms = ev.ms(1, 2);
  m.times.scan_ms = reuse ? 0.0 : ev.ms(2, 3);
  m.times.reuse_ms = reuse ? ev.ms(2, 3) + ev.ms(4, 5) : 0.0;
  m.times.ao_ms = ev.ms(3, 4);
  m.times.shade_ms = ev.ms(last - 1, last);
  m.times.total_ms = ev.ms(0, last);
  // Copy back what was asked for
  const Timer download;
  FrameCounters counters{};
  m.counters.download(&counters, 1);
  f.color = Image(w, h, 3);
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
  m.color.download(reinterpret_cast<glm::vec3*>(f.color.pixels.data()), n);
  if (outputs.visibility) {
    f.visibility.resize(n);
    FOVEAL_CUDA_CHECK(cudaMemcpy(f.visibility.data(), visibility, n * sizeof(float), cudaMemcpyDeviceToHost));
    if (reuse) {
      f.ao_traced.resize(n);
      m.traced.download(f.ao_traced.data(), n);
    }
  }
  if (outputs.maps) {
    f.maps.width = w;
    f.maps.height = h;
    f.maps.quality.resize(n);
    f.maps.eccentricity.resize(n);
    f.maps.rays.resize(n);
    f.maps.blend.resize(n);
    m.quality.download(f.maps.quality.data(), n);
    m.eccentricity.download(f.maps.eccentricity.data(), n);
    m.rays.download(f.maps.rays.data(), n);
    m.blend.download(f.maps.blend.data(), n);
  }
  if (outputs.gbuffer) {
    GBuffer& gb = f.gbuffer;
    gb.width = w;
    gb.height = h;
    gb.prim.resize(n);
    for (auto* v : {&gb.position, &gb.normal, &gb.geo_normal, &gb.albedo, &gb.view}) v->resize(n);
    gb.depth.resize(n);
    m.prim.download(gb.prim.data(), n);
    m.position.download(gb.position.data(), n);
    m.normal.download(gb.normal.data(), n);
    m.geo_normal.download(gb.geo_normal.data(), n);
    m.albedo.download(gb.albedo.data(), n);
    m.view.download(gb.view.data(), n);
    m.depth.download(gb.depth.data(), n);
  }
  m.times.download_ms = download.ms();
  // Stats as the CPU renderer reports them; times are the GPU's
  FrameStats& s = f.stats;
  s.primary_ms = m.times.primary_ms;
  s.foveation_ms = m.times.foveation_ms;
  s.ao_ms = m.times.scan_ms + m.times.ao_ms;
  s.shade_ms = m.times.shade_ms;
  s.total_ms = m.times.total_ms;
  s.primary_rays = n;
  s.ao_rays = counters.total_rays;
  s.shadow_rays = counters.shadow_rays;
  s.ao_rays_mean = static_cast<double>(s.ao_rays) / static_cast<double>(n);
  s.ao_rays_min = counters.min_rays == std::numeric_limits<int>::max() ? 0 : counters.min_rays;
  s.ao_rays_max = counters.max_rays;
  s.ambient_constant = params.ambient_constant ? *params.ambient_constant
                       : reuse                 ? fovea_mean_reused_visibility(counters)
                                               : fovea_mean_visibility(counters, params.foveation.max_rays);
  s.history_pixels = counters.history_pixels;
  s.denoised_pixels = counters.denoised_pixels;
  s.reuse_ms = m.times.reuse_ms;
  s.ao_distance = ao_distance;
  return f;
}

void Renderer::intersect(std::span<const Ray> rays, std::span<Hit> hits) {
  Impl& m = *impl_;
  if (hits.size() < rays.size()) throw Error("gpu::Renderer::intersect: fewer hits than rays");
  m.raw_rays.upload(rays.data(), rays.size());
  m.raw_hits.reserve(rays.size());
  intersect_kernel<<<blocks_for(rays.size(), 128), 128>>>(m.bvh_view(), m.raw_rays.get(), m.raw_hits.get(), rays.size());
  FOVEAL_CUDA_LAUNCHED("intersect");
  m.raw_hits.download(hits.data(), rays.size());
}

namespace {

void upload_task_surfaces(Renderer::Impl& m, const GBuffer& g, uint64_t version) {
  if (m.tasks.uploaded && m.tasks.version == version) return;
  m.tasks.position.upload(g.position);
  m.tasks.geo_normal.upload(g.geo_normal);
  m.tasks.version = version;
  m.tasks.uploaded = true;
}

}  // namespace

GBuffer Renderer::surfaces(const Camera& camera, int width, int height) {
  if (width < 1 || height < 1)
    throw Error("gpu::Renderer::surfaces: a view of " + std::to_string(width) + "x" + std::to_string(height) + " pixels has none");
  Impl& m = *impl_;
  const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
  for (auto* a : {&m.position, &m.geo_normal, &m.normal, &m.albedo, &m.view}) a->reserve(n);
  m.depth.reserve(n);
  m.prim.reserve(n);
  const detail::GBufferPtrs g{m.prim.get(),   m.position.get(), m.geo_normal.get(), m.normal.get(),
                              m.albedo.get(), m.view.get(),     m.depth.get()};
  const dim3 block2d(16, 8), grid2d((width + 15) / 16, (height + 7) / 8);
  primary_kernel<<<grid2d, block2d>>>(m.bvh_view(), m.scene_view(), CameraRays(camera, width, height), width, height, g);
  FOVEAL_CUDA_LAUNCHED("primary rays (surfaces)");
  // Into page-locked memory, then into the G-buffer's arrays on the host's threads, each array
  // built from its copy in one pass. A frame's own copy-back, into freshly zeroed arrays of ordinary
  // memory with its colour and the frame's other passes, took 8–20 ms at 840x525 on an H200 with
  // 16 Xeon threads (0.3 ms of it the GPU's): most of what a moving camera's view cost there.
  const size_t words = n * sizeof(uint32_t), vec3s = n * sizeof(glm::vec3);
  static_assert(sizeof(float) == sizeof(uint32_t) && sizeof(glm::vec3) == 3 * sizeof(float));
  m.staging.reserve(2 * words + 5 * vec3s);
  unsigned char* const staged = m.staging.get();
  glm::vec3* const vec3_part = reinterpret_cast<glm::vec3*>(staged + 2 * words);
  FOVEAL_CUDA_CHECK(cudaMemcpyAsync(staged, m.prim.get(), words, cudaMemcpyDeviceToHost));
  FOVEAL_CUDA_CHECK(cudaMemcpyAsync(staged + words, m.depth.get(), words, cudaMemcpyDeviceToHost));
  const glm::vec3* const from[5] = {m.position.get(), m.normal.get(), m.geo_normal.get(), m.albedo.get(), m.view.get()};
  for (size_t k = 0; k < 5; ++k) FOVEAL_CUDA_CHECK(cudaMemcpyAsync(vec3_part + k * n, from[k], vec3s, cudaMemcpyDeviceToHost));
  FOVEAL_CUDA_CHECK(cudaStreamSynchronize(nullptr));
  FOVEAL_CUDA_CHECK(cudaGetLastError());  // a fault inside the kernel
  GBuffer gb;
  gb.width = width;
  gb.height = height;
  const auto* prim = reinterpret_cast<const uint32_t*>(staged);
  const auto* depth = reinterpret_cast<const float*>(staged + words);
  std::vector<glm::vec3>* const to[5] = {&gb.position, &gb.normal, &gb.geo_normal, &gb.albedo, &gb.view};
  tbb::parallel_for(0, 7, [&](int k) {
    if (k == 0)
      gb.prim.assign(prim, prim + n);
    else if (k == 1)
      gb.depth.assign(depth, depth + n);
    else
      to[k - 2]->assign(vec3_part + static_cast<size_t>(k - 2) * n, vec3_part + static_cast<size_t>(k - 1) * n);
  });
  return gb;
}

void Renderer::prepare_ao_tasks(const GBuffer& surfaces, uint64_t version) {
  Impl& m = *impl_;
  upload_task_surfaces(m, surfaces, version);
  const size_t pixels = surfaces.prim.size();
  m.tasks.list.reserve(pixels);
  m.tasks.offset.reserve(pixels + 1);
  m.tasks.blocked.reserve(pixels);
  m.tasks.host_offset.reserve(pixels + 1);
  if (!m.tasks.loaded) {  // a launch without rays loads the kernel (CUDA loads modules lazily)
    const unsigned long long zero = 0;
    m.tasks.offset.upload(&zero, 1);
    const AoTaskArgs a{m.bvh_view(), nullptr, nullptr, nullptr, m.tasks.offset.get(), nullptr, m.sobol.get(), 0, 0, 1, 1.0f, 0.0f, 1};
    ao_tasks_kernel<<<1, 32>>>(a);
    FOVEAL_CUDA_LAUNCHED("ao tasks (loading)");
    FOVEAL_CUDA_CHECK(cudaDeviceSynchronize());
    m.tasks.loaded = true;
  }
}

uint64_t Renderer::trace_ao_tasks(const AoRayBatch& batch) {
  Impl& m = *impl_;
  const GBuffer& g = *batch.gbuffer;
  const size_t count = batch.tasks.size();
  if (batch.blocked.size() < count || batch.done.size() < count)
    throw Error("gpu::Renderer::trace_ao_tasks: output spans shorter than the tasks");
  upload_task_surfaces(m, g, batch.gbuffer_version);
  // The tasks' rays end to end; a task whose pixel missed the scene casts none
  std::vector<unsigned long long>& offset = m.tasks.host_offset;
  offset.resize(count + 1);
  unsigned long long rays = 0;
  for (size_t t = 0; t < count; ++t) {
    offset[t] = rays;
    const AoRayTask& task = batch.tasks[t];
    if (task.pixel < g.prim.size() && g.hit(task.pixel)) rays += task.count;
  }
  offset[count] = rays;
  std::fill(batch.done.begin(), batch.done.begin() + static_cast<std::ptrdiff_t>(count), uint8_t{0});
  if (count == 0) return 0;
  m.tasks.list.upload(batch.tasks.data(), count);
  m.tasks.offset.upload(offset);
  m.tasks.blocked.reserve(count);
  FOVEAL_CUDA_CHECK(cudaMemset(m.tasks.blocked.get(), 0, count * sizeof(uint32_t)));
  // Launches of about kTaskLaunchRays rays, in the tasks' (priority) order; where the caller has a
  // deadline each launch is waited for and the deadline asked before the next, so that a batch
  // planned past it stops at a launch's end, as the CPU's stops at a chunk's
  size_t launched = 0;
  while (launched < count) {
    if (batch.expired && batch.expired()) break;
    const auto end = static_cast<size_t>(
        std::lower_bound(offset.begin() + static_cast<std::ptrdiff_t>(launched) + 1, offset.end() - 1, offset[launched] + kTaskLaunchRays) -
        offset.begin());
    const size_t last = std::max(end, launched + 1);
    const unsigned long long launch_rays = offset[last] - offset[launched];
    if (launch_rays > 0) {
      const AoTaskArgs a{m.bvh_view(),
                         m.tasks.position.get(),
                         m.tasks.geo_normal.get(),
                         m.tasks.list.get(),
                         m.tasks.offset.get(),
                         m.tasks.blocked.get(),
                         m.sobol.get(),
                         launched,
                         last,
                         g.width,
                         batch.ao_distance,
                         batch.epsilon,
                         batch.seed};
      const unsigned blocks =
          std::min<unsigned>(static_cast<unsigned>(m.ao_grid), blocks_for((launch_rays + detail::kAoChunk - 1) / detail::kAoChunk, 128));
      ao_tasks_kernel<<<blocks, 128>>>(a);
      FOVEAL_CUDA_LAUNCHED("ao tasks");
      if (batch.expired) FOVEAL_CUDA_CHECK(cudaDeviceSynchronize());
    }
    launched = last;
  }
  m.tasks.blocked.download(batch.blocked.data(), launched);
  std::fill(batch.done.begin(), batch.done.begin() + static_cast<std::ptrdiff_t>(launched), uint8_t{1});
  return offset[launched];
}

void Renderer::occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) {
  Impl& m = *impl_;
  if (occluded.size() < rays.size()) throw Error("gpu::Renderer::occluded: fewer results than rays");
  m.raw_rays.upload(rays.data(), rays.size());
  m.raw_occluded.reserve(rays.size());
  occluded_kernel<<<blocks_for(rays.size(), 128), 128>>>(m.bvh_view(), m.raw_rays.get(), m.raw_occluded.get(), rays.size());
  FOVEAL_CUDA_LAUNCHED("occluded");
  m.raw_occluded.download(occluded.data(), rays.size());
}

namespace {

// Rays per second of `launch` over `rays` rays already on the GPU: the median of `repeats` timed
// launches after a warm-up, CUDA events around each.
template <class Launch>
double median_rate(PassEvents& ev, size_t rays, int repeats, const Launch& launch) {
  launch();  // warm-up
  std::vector<double> times;
  for (int r = 0; r < std::max(1, repeats); ++r) {
    ev.record(0);
    launch();
    ev.record(1);
    FOVEAL_CUDA_CHECK(cudaEventSynchronize(ev.e[1]));
    times.push_back(ev.ms(0, 1));
  }
  std::sort(times.begin(), times.end());
  const double median_ms = times[times.size() / 2];
  return median_ms > 0 ? static_cast<double>(rays) / (median_ms * 1e-3) : 0.0;
}

// Raw any-hit or closest-hit rays per second of the scene's BVH on `rays`.
double raw_rate(Renderer::Impl& m, std::span<const Ray> rays, int repeats, bool any_hit) {
  if (rays.empty()) return 0;
  m.raw_rays.upload(rays.data(), rays.size());
  if (any_hit)
    m.raw_occluded.reserve(rays.size());
  else
    m.raw_hits.reserve(rays.size());
  return median_rate(m.events, rays.size(), repeats, [&] {
    const unsigned blocks = blocks_for(rays.size(), 128);
    if (any_hit)
      occluded_kernel<<<blocks, 128>>>(m.bvh_view(), m.raw_rays.get(), m.raw_occluded.get(), rays.size());
    else
      intersect_kernel<<<blocks, 128>>>(m.bvh_view(), m.raw_rays.get(), m.raw_hits.get(), rays.size());
    FOVEAL_CUDA_LAUNCHED(any_hit ? "occluded" : "intersect");
  });
}

}  // namespace

double Renderer::measure_occlusion_rate(std::span<const Ray> rays, int repeats) { return raw_rate(*impl_, rays, repeats, true); }

double Renderer::measure_intersection_rate(std::span<const Ray> rays, int repeats) { return raw_rate(*impl_, rays, repeats, false); }

}  // namespace foveal::gpu
