// foveal/cuda/gpu.h — the CUDA backend: both pipelines' passes on an NVIDIA GPU.
//
// This header has no CUDA types, so every part of foveal includes it whether or not the build
// found a CUDA toolkit. Without one (or without a GPU at run time) availability() says why,
// and constructing a gpu::Renderer throws an Error with that reason.
//
// The GPU renderer runs the CPU renderer's passes (render.h) as kernels over device memory:
// primary rays through a BVH built on the CPU by Embree's SAH builder (trace/bvh.h), the
// foveation model, foveated AO with per-pixel ray counts, and Phong shading. The per-pixel
// code is the CPU's own (render/pixel.h, perception/foveation.h, util/sampling.h); the
// buffers stay on the GPU between passes, and only what the caller asks for is copied back.
#pragma once

#include "foveal/render/frame_renderer.h"
#include "foveal/render/render.h"
#include "foveal/trace/bvh.h"
#include "foveal/util/device.h"
#include "foveal/vision/blur.h"
#include "foveal/vision/coc.h"
#include "foveal/vision/features.h"
#include "foveal/vision/passes.h"
#include "foveal/vision/sharpness.h"

#include <memory>
#include <span>
#include <string>

namespace foveal::gpu {

// How the AO pass spreads rays over GPU threads.
enum class AoSchedule {
  balanced,   // every thread traces the same number of rays (a prefix sum over the per-pixel counts)
  per_pixel,  // one thread per pixel loops over its own n(E) rays (the papers' OptiX layout)
};
const char* to_string(AoSchedule schedule);

// GPU times of one frame's passes, milliseconds (CUDA events).
struct GpuPassTimes {
  double primary_ms = 0, foveation_ms = 0, scan_ms = 0, ao_ms = 0, shade_ms = 0, total_ms = 0;
  double reuse_ms = 0;     // quality per ray: reprojection, visibility, filter and history (not AO)
  double download_ms = 0;  // copying the asked-for buffers back (host clock)
};

// One scene on the GPU: its BVH, triangles, materials and textures, and the frame buffers.
class Renderer {
 public:
  // Builds the BVH and uploads the scene; throws Error when the backend is unavailable.
  explicit Renderer(const Scene& scene);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // One frame, as render_frame() on the CPU: the same RenderParams, the same Frame. With
  // params.reuse (adaptive rays, the filter, temporal reuse) the CPU's passes run as kernels over
  // the same per-pixel functions (render/reuse_pixel.h), the AO pass in rounds (with the balanced
  // schedule a launch per round over every pixel's rays of it, with the per-pixel schedule a thread
  // per pixel: the same frame); with params.reuse.temporal the frame builds on the history the Renderer keeps
  // from its last temporal frame (render_frame's AoHistory) and leaves its own there. Frames
  // without temporal neither read nor change it. outputs.visibility also brings back
  // Frame::ao_traced when params.reuse is on.
  // FrameOutputs (render/frame_renderer.h): which buffers come back besides the colour.
  Frame render(const Camera& camera, const RenderParams& params, const FrameOutputs& outputs = {});
  // Forget the temporal history: the next temporal frame is the paper's frame.
  void reset_history();
  uint32_t history_frames() const;  // temporal frames stored since the last reset
  const GpuPassTimes& last_times() const;

  void set_ao_schedule(AoSchedule schedule);
  AoSchedule ao_schedule() const;
  const Bvh& bvh() const;

  // The view's surfaces alone (FrameRenderer::surfaces): the primary rays' G-buffer, without a
  // frame's maps, AO or shading, copied back through page-locked memory.
  GBuffer surfaces(const Camera& camera, int width, int height);

  // AO rays continuing pixels' sequences (FrameRenderer::trace_ao_batch) from the G-buffer's
  // surfaces, uploaded when batch.gbuffer_version changes: the tasks' rays laid end to end and
  // spread evenly over the GPU's threads, in launches of about two million rays; with
  // batch.expired, the deadline is asked before each launch.
  uint64_t trace_ao_tasks(const AoRayBatch& batch);
  // Uploads the surfaces (when `version` is new), sizes the buffers for one task per pixel and loads
  // the kernel, so that the next trace_ao_tasks() pays none of it.
  void prepare_ao_tasks(const GBuffer& surfaces, uint64_t version);

  // Raw tracing of given rays on the GPU (tests, and the GPU's own throughput baseline).
  void intersect(std::span<const Ray> rays, std::span<Hit> hits);
  void occluded(std::span<const Ray> rays, std::span<uint8_t> occluded);
  // Occlusion rays per second on the given rays (already on the GPU when the clock starts).
  double measure_occlusion_rate(std::span<const Ray> rays, int repeats = 5);
  // Closest-hit rays per second on the given rays, likewise (the baseline of a primary-ray pass).
  double measure_intersection_rate(std::span<const Ray> rays, int repeats = 5);

  struct Impl;

 private:
  friend class VisionPasses;
  std::unique_ptr<Impl> impl_;
};

// The second paper's passes for one scene on the GPU: the ray-cast image, FAST corners, the
// sharpness field (kept on the GPU), each pixel's CoC and the variable blur. VisionSimulation
// (vision/simulate.h) drives it a step at a time; the saccade model chooses among the corners on
// the CPU. The per-pixel code is the CPU's (vision/fast.h, coc.h, sharpness.h, blur_kernel.h).
class VisionPasses {
 public:
  // Uploads the scene and an empty field with `field`'s grid and starvation; throws Error when
  // the backend is unavailable.
  VisionPasses(const Scene& scene, const SharpnessField& field, const BlurParams& blur);
  ~VisionPasses();
  VisionPasses(const VisionPasses&) = delete;
  VisionPasses& operator=(const VisionPasses&) = delete;

  // Primary rays and Phong shading with a constant ambient factor (no shadows), kept on the GPU.
  void trace(const Camera& camera, int width, int height, float ambient);
  // FAST-9 corners of the traced image (cv::FAST's, see vision/fast.h), by row then column.
  std::vector<Corner> corners(int threshold, bool nonmax_suppression = true);
  // The hit distance along pixel (x, y)'s ray (infinity for the background), and the ray.
  float depth_at(int x, int y, glm::vec3* view);
  // A blink: every cell of the field becomes unseen.
  void blink();
  // This step's CoC per pixel, the field's update with it (unless `update` is false: glaucoma's
  // skipped steps), and the blur's CoC in pixels (the field's memory where there is geometry);
  // returns how many pixels' CoC is below `sharp_px`.
  size_t sharpness(const CocModel& model, uint32_t step, bool update, float pixels_per_degree, float sharp_px);
  // The variable blur of the traced image with the last sharpness()'s CoCs (elliptical with the
  // model's shape when it was astigmatic, the cylinder's axis at `axis_deg`).
  void blur(float axis_deg);
  // An impaired eye's media, retina and colour on the blurred image, in place (perceived() is then
  // the impaired image): ImpairmentPasses::apply's operations in its order, each pixel by the CPU's
  // rules (the models' own, and OpenCV's resampling as impair/resample.h computes it), the glare's
  // convolution summed directly on its coarse grid (cuda/gpu_impair.cu). Times from CUDA events.
  ImpairTimes impair(const ImpairmentPasses& passes, const CameraRetinotopy& where);

  Image color() const;      // the traced image
  Image perceived() const;  // the blurred one
  std::vector<float> coc_px() const;
  const VisionPassTimes& last_times() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace foveal::gpu
