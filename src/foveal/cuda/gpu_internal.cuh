// foveal/cuda/gpu_internal.cuh — what the CUDA backend's translation units share: device
// arrays, error checks, pass timing, the scene on the GPU (Renderer::Impl) and the primary-ray
// kernel. Included only by .cu files.
#pragma once

#include "foveal/cuda/gpu.h"
#include "foveal/cuda/reuse_kernels.h"

#include "foveal/render/pixel.h"
#include "foveal/util/error.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

namespace foveal::gpu {
namespace detail {

inline void check(cudaError_t status, const char* what) {
  if (status != cudaSuccess) throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(status));
}
#define FOVEAL_CUDA_CHECK(call) ::foveal::gpu::detail::check((call), #call)
// After a launch: the launch's own error (bad configuration), not waiting for the kernel
#define FOVEAL_CUDA_LAUNCHED(name) ::foveal::gpu::detail::check(cudaGetLastError(), name)

// A growable device array of T; contents are not kept when it grows.
template <class T>
class DeviceArray {
 public:
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (ptr_) cudaFree(ptr_);
  }
  void reserve(size_t count) {
    if (count <= capacity_) return;
    if (ptr_) cudaFree(ptr_);
    ptr_ = nullptr;
    capacity_ = 0;
    FOVEAL_CUDA_CHECK(cudaMalloc(&ptr_, std::max<size_t>(count, 1) * sizeof(T)));
    capacity_ = count;
  }
  void upload(const T* data, size_t count) {
    reserve(count);
    if (count) FOVEAL_CUDA_CHECK(cudaMemcpy(ptr_, data, count * sizeof(T), cudaMemcpyHostToDevice));
  }
  void upload(const std::vector<T>& v) { upload(v.data(), v.size()); }
  void download(T* data, size_t count) const {
    if (count) FOVEAL_CUDA_CHECK(cudaMemcpy(data, ptr_, count * sizeof(T), cudaMemcpyDeviceToHost));
  }
  T* get() const { return ptr_; }

 private:
  T* ptr_ = nullptr;
  size_t capacity_ = 0;
};

// Growable page-locked host memory, which the GPU copies into at the bus's speed (a copy into
// ordinary memory goes through the driver's own buffers); contents are not kept when it grows.
class PinnedBuffer {
 public:
  PinnedBuffer() = default;
  PinnedBuffer(const PinnedBuffer&) = delete;
  PinnedBuffer& operator=(const PinnedBuffer&) = delete;
  ~PinnedBuffer() {
    if (ptr_) cudaFreeHost(ptr_);
  }
  void reserve(size_t bytes) {
    if (bytes <= capacity_) return;
    if (ptr_) cudaFreeHost(ptr_);
    ptr_ = nullptr;
    capacity_ = 0;
    FOVEAL_CUDA_CHECK(cudaMallocHost(&ptr_, std::max<size_t>(bytes, 1)));
    capacity_ = bytes;
  }
  unsigned char* get() const { return static_cast<unsigned char*>(ptr_); }

 private:
  void* ptr_ = nullptr;
  size_t capacity_ = 0;
};

// Counters one frame accumulates on the GPU, read back once at its end.
struct FrameCounters {
  unsigned long long total_rays;    // AO rays of the frame (the prefix sum's total)
  unsigned long long fovea_open;    // unblocked AO rays of pixels with q = 1 (the `auto` ambient constant)
  unsigned long long fovea_pixels;  // pixels with q = 1, a hit and rays
  unsigned long long shadow_rays;
  int min_rays, max_rays;  // over pixels that hit the scene
  // Quality per ray (zero without it)
  unsigned long long fovea_visibility;  // Σ V over the q = 1 pixels in units of 2⁻³² (exact, any order)
  unsigned long long history_pixels;    // pixels whose reprojected history was kept
  unsigned long long denoised_pixels;   // pixels the filter changed
};
inline constexpr double kFoveaVisibilityUnit = 4294967296.0;  // 2³²

// The `auto` ambient constant: the mean visibility of the q = 1 pixels, all of which trace n_max
// rays, from the frame's integer sums (exact, and the same in any summation order).
__host__ __device__ inline float fovea_mean_visibility(const FrameCounters& f, int max_rays) {
  return f.fovea_pixels > 0 && max_rays > 0
             ? static_cast<float>(static_cast<double>(f.fovea_open) / (static_cast<double>(f.fovea_pixels) * max_rays))
             : 1.0f;
}

// The `auto` ambient constant of a frame with quality per ray, whose visibilities are not open / n_max:
// the mean of the q = 1 pixels' V from their fixed-point sum.
__host__ __device__ inline float fovea_mean_reused_visibility(const FrameCounters& f) {
  return f.fovea_pixels > 0
             ? static_cast<float>(static_cast<double>(f.fovea_visibility) / kFoveaVisibilityUnit / static_cast<double>(f.fovea_pixels))
             : 1.0f;
}

struct GBufferPtrs {
  uint32_t* prim;
  glm::vec3* position;
  glm::vec3* geo_normal;
  glm::vec3* normal;
  glm::vec3* albedo;
  glm::vec3* view;
  float* depth;
};

inline unsigned blocks_for(size_t count, unsigned threads) { return static_cast<unsigned>((count + threads - 1) / threads); }
// Blocks covering a w × h image (and `depth` layers).
inline dim3 grid_for(int w, int h, dim3 block, int depth = 1) {
  return dim3((w + block.x - 1) / block.x, (h + block.y - 1) / block.y, depth);
}

// The balanced AO passes' consecutive rays per GPU thread.
constexpr int kAoChunk = 8;

// The last of the entries [lo, hi) whose offset (an exclusive prefix sum of rays) is ≤ r: the one
// whose rays hold ray r. Entries without rays share their successor's offset and come before it.
__device__ inline size_t holder_of(const unsigned long long* offset, size_t lo, size_t hi, unsigned long long r) {
  while (hi - lo > 1) {
    const size_t mid = (lo + hi) / 2;
    if (offset[mid] <= r)
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}

// Events that time the passes of one frame on the default stream.
struct PassEvents {
  cudaEvent_t e[8] = {};
  PassEvents() {
    for (auto& ev : e) FOVEAL_CUDA_CHECK(cudaEventCreate(&ev));
  }
  ~PassEvents() {
    for (auto& ev : e) cudaEventDestroy(ev);
  }
  void record(int k) { FOVEAL_CUDA_CHECK(cudaEventRecord(e[k])); }
  double ms(int a, int b) const {
    float t = 0;
    FOVEAL_CUDA_CHECK(cudaEventElapsedTime(&t, e[a], e[b]));
    return t;
  }
};

// An impaired eye's passes over an image on the GPU (cuda/gpu_impair.cu; VisionPasses::impair), with
// their buffers, the glare's kernel and the field's map kept from one step to the next.
class ImpairKernels {
 public:
  ImpairKernels();
  ~ImpairKernels();
  ImpairKernels(const ImpairKernels&) = delete;
  ImpairKernels& operator=(const ImpairKernels&) = delete;
  // In place on `rgb` (width × height, three floats a pixel, on the GPU).
  ImpairTimes apply(const ImpairmentPasses& passes, const CameraRetinotopy& where, float* rgb, int width, int height);

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace detail

struct Renderer::Impl {
  using FrameCounters = detail::FrameCounters;
  template <class T>
  using DeviceArray = detail::DeviceArray<T>;
  using PassEvents = detail::PassEvents;
  Bvh bvh;
  size_t triangle_count = 0;
  AoSchedule schedule = AoSchedule::balanced;
  GpuPassTimes times;
  PassEvents events;  // timing the passes of each frame
  int ao_grid = 0;    // blocks of the balanced AO kernel (a full GPU)

  // Scene
  DeviceArray<BvhNode> nodes;
  DeviceArray<BvhTriangle> triangles;
  DeviceArray<glm::vec3> positions, normals;
  DeviceArray<glm::vec2> uvs;
  DeviceArray<glm::uvec3> tris;
  DeviceArray<uint32_t> material_ids;
  DeviceArray<MaterialView> materials;
  DeviceArray<TextureView> textures;
  DeviceArray<uint8_t> texels;
  DeviceArray<float> srgb_lut;
  DeviceArray<uint32_t> sobol;
  DeviceArray<Light> lights;
  std::vector<Light> scene_lights;
  glm::vec3 ambient{0.6f};
  float epsilon = 0;
  float default_ao_distance = 0;

  // Frame
  DeviceArray<uint32_t> prim;
  DeviceArray<glm::vec3> position, geo_normal, normal, albedo, view, color;
  DeviceArray<float> depth, quality, eccentricity, blend, visibility;
  DeviceArray<uint16_t> rays;
  DeviceArray<unsigned long long> ray_count, offset;
  DeviceArray<uint32_t> blocked;
  DeviceArray<FrameCounters> counters;
  DeviceArray<uint8_t> scan_temp;
  size_t scan_temp_bytes = 0;

  // Quality per ray (cuda/gpu_reuse.cu): the frame's AO ray counts, the filter's output, and the
  // history of the last temporal frame, kept on the GPU between frames
  DeviceArray<float> count_open, count_cast, filtered;
  DeviceArray<glm::vec3> count_origin;
  DeviceArray<uint16_t> traced;
  DeviceArray<AoRoundState> round_state;       // the balanced schedule's rounds (gpu_reuse.cu)
  DeviceArray<unsigned long long> round_rays;  // … one round's rays in all
  struct History {
    DeviceArray<glm::vec3> position, normal, origin;
    DeviceArray<uint8_t> hit;
    DeviceArray<float> open, cast;
    Camera camera;
    int width = 0, height = 0;
    uint32_t frames = 0;  // stored since the last reset
  } history;

  // A view's surfaces on their way to the host (Renderer::surfaces)
  detail::PinnedBuffer staging;

  // AO tasks (the real-time loop): the surfaces of the last G-buffer version, the tasks, results
  struct Tasks {
    DeviceArray<glm::vec3> position, geo_normal;
    uint64_t version = 0;
    bool uploaded = false;
    bool loaded = false;  // the kernel has been launched once
    DeviceArray<AoRayTask> list;
    std::vector<unsigned long long> host_offset;  // the tasks' prefix sum of rays, made on the host
    DeviceArray<unsigned long long> offset;
    DeviceArray<uint32_t> blocked;
  } tasks;

  // Raw tracing
  DeviceArray<Ray> raw_rays;
  DeviceArray<Hit> raw_hits;
  DeviceArray<uint8_t> raw_occluded;

  BvhView bvh_view() const { return {nodes.get(), triangles.get()}; }
  SceneView scene_view() const {
    SceneView v;
    v.positions = positions.get();
    v.normals = normals.get();
    v.uvs = uvs.get();
    v.triangles = tris.get();
    v.material_ids = material_ids.get();
    v.materials = materials.get();
    v.textures = textures.get();
    v.srgb_lut = srgb_lut.get();
    return v;
  }
};

namespace detail {

// The reuse passes of one frame (cuda/gpu_reuse.cu), after the primary rays and the foveation
// maps: reprojection of the history, the AO pass in adaptive rounds on the history, visibility,
// the filter, and the history kept for the next frame. Leaves V in the returned device buffer,
// the frame's counters on the GPU, and records events 2 (start), 3 (after reprojection), 4 (after AO)
// and 5 (after visibility, filter and history).
struct ReuseFrame {
  const Camera* camera;
  const RenderParams* params;
  float ao_distance;
  size_t pixels;
};
float* run_reuse_passes(Renderer::Impl& m, const ReuseFrame& frame);

}  // namespace detail

namespace {

__global__ void primary_kernel(BvhView bvh, SceneView scene, CameraRays camera, int width, int height, detail::GBufferPtrs g) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= width || y >= height) return;
  const size_t i = static_cast<size_t>(y) * width + x;
  const Ray ray = camera(x + 0.5, y + 0.5);
  g.view[i] = ray.dir;
  Hit h;
  if (!bvh_trace<false>(bvh, ray, &h)) {
    g.prim[i] = Hit::kNoHit;
    g.depth[i] = std::numeric_limits<float>::infinity();
    g.position[i] = g.geo_normal[i] = g.normal[i] = g.albedo[i] = glm::vec3(0.0f);
    return;
  }
  const Surface s = surface_at(scene, h, ray.dir);
  g.prim[i] = h.prim;
  g.depth[i] = h.t;
  g.position[i] = s.position;
  g.geo_normal[i] = s.geo_normal;
  g.normal[i] = s.normal;
  g.albedo[i] = s.albedo;
}

}  // namespace
}  // namespace foveal::gpu
