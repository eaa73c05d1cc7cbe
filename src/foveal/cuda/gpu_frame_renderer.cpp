// foveal/cuda/gpu_frame_renderer.cpp — the CUDA backend's FrameRenderer (render/frame_renderer.h):
// gpu::Renderer, which keeps the temporal history in device memory, behind the device-neutral
// interface. In a build without CUDA, gpu::Renderer's stub throws the reason on construction.
#include "foveal/cuda/gpu.h"
#include "foveal/render/frame_renderer.h"

namespace foveal {

namespace {

class GpuFrameRenderer final : public FrameRenderer {
 public:
  explicit GpuFrameRenderer(const Scene& scene) : gpu_(scene), triangles_(scene.triangles.size()) {}

  Frame render(const Camera& camera, const RenderParams& params, const FrameOptions& options) override {
    if (options.use_history || !params.reuse.temporal) return gpu_.render(camera, params, options.outputs);
    RenderParams apart = params;  // a frame apart: the GPU's frames without temporal leave the history alone
    apart.reuse.temporal = false;
    return gpu_.render(camera, apart, options.outputs);
  }
  void reset_history() override { gpu_.reset_history(); }
  uint32_t history_frames() const override { return gpu_.history_frames(); }
  uint64_t trace_ao_batch(const AoRayBatch& batch) override { return gpu_.trace_ao_tasks(batch); }
  void prepare_ao_batches(const GBuffer& surfaces, uint64_t version) override { gpu_.prepare_ao_tasks(surfaces, version); }
  GBuffer surfaces(const Camera& camera, int width, int height) override { return gpu_.surfaces(camera, width, height); }
  double raw_occlusion_rays_per_ms(std::span<const Ray> rays) override { return gpu_.measure_occlusion_rate(rays) / 1000; }
  ComputeDevice device() const override { return ComputeDevice::cuda; }
  size_t triangles() const override { return triangles_; }
  double build_ms() const override { return gpu_.bvh().build_ms; }
  std::string trace_api() const override { return "bvh2"; }

 private:
  gpu::Renderer gpu_;
  size_t triangles_;
};

}  // namespace

std::unique_ptr<FrameRenderer> make_cuda_frame_renderer(const Scene& scene) { return std::make_unique<GpuFrameRenderer>(scene); }

}  // namespace foveal
