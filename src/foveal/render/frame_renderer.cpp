// foveal/render/frame_renderer.cpp — the CPU's FrameRenderer: render_frame() over an Embree tracer,
// with the temporal history it keeps between frames.
#include "foveal/render/frame_renderer.h"

#include "foveal/render/reuse.h"
#include "foveal/util/error.h"

namespace foveal {

namespace {

class CpuFrameRenderer final : public FrameRenderer {
 public:
  CpuFrameRenderer(const Scene& scene, TraceApi api) : scene_(scene), owned_(std::make_unique<Tracer>(scene, api)), tracer_(*owned_) {}
  CpuFrameRenderer(const Scene& scene, const Tracer& tracer) : scene_(scene), tracer_(tracer) {}

  Frame render(const Camera& camera, const RenderParams& params, const FrameOptions& options) override {
    return render_frame(tracer_, scene_, camera, params, options.progress, options.use_history ? &history_ : nullptr);
  }
  void reset_history() override { history_.clear(); }
  uint32_t history_frames() const override { return history_.frames(); }
  uint64_t trace_ao_batch(const AoRayBatch& batch) override { return trace_ao_tasks(tracer_, batch); }
  GBuffer surfaces(const Camera& camera, int width, int height) override { return trace_primary(tracer_, scene_, camera, width, height); }
  GBuffer surfaces_rows(const Camera& camera, int width, int height, int y0, int y1) override {
    return trace_primary_rows(tracer_, scene_, camera, width, height, y0, y1);
  }
  double raw_occlusion_rays_per_ms(std::span<const Ray> rays) override {
    return measure_raw_occlusion(tracer_, rays, TraceApi::stream).rays_per_second / 1000;
  }
  ComputeDevice device() const override { return ComputeDevice::cpu; }
  size_t triangles() const override { return tracer_.triangles(); }
  double build_ms() const override { return tracer_.build_ms(); }
  std::string trace_api() const override { return to_string(tracer_.occlusion_api()); }

 private:
  const Scene& scene_;
  std::unique_ptr<Tracer> owned_;
  const Tracer& tracer_;
  AoHistory history_;
};

}  // namespace

GBuffer FrameRenderer::surfaces(const Camera& camera, int width, int height) {
  RenderParams p;
  p.width = width;
  p.height = height;
  p.foveation.max_rays = p.foveation.min_rays = 0;
  FrameOptions options;
  options.outputs = {false, false, true};
  options.use_history = false;
  return render(camera, p, options).gbuffer;
}

GBuffer FrameRenderer::surfaces_rows(const Camera& camera, int width, int height, int y0, int y1) {
  if (y0 < 0 || y1 > height || y0 >= y1) fail("surfaces_rows: rows [{}, {}) are not inside 0..{}", y0, y1, height);
  GBuffer all = surfaces(camera, width, height);
  if (y0 == 0) return all;
  const size_t from = static_cast<size_t>(y0) * static_cast<size_t>(width);
  GBuffer g;
  g.width = width;
  g.height = height - y0;
  auto tail = [&](auto& v) { return std::vector(v.begin() + static_cast<std::ptrdiff_t>(from), v.end()); };
  g.prim = tail(all.prim);
  g.position = tail(all.position);
  g.normal = tail(all.normal);
  g.geo_normal = tail(all.geo_normal);
  g.albedo = tail(all.albedo);
  g.depth = tail(all.depth);
  g.view = tail(all.view);
  return g;
}

std::unique_ptr<FrameRenderer> make_frame_renderer(const Scene& scene, ComputeDevice device, TraceApi api) {
  if (device == ComputeDevice::cuda) return make_cuda_frame_renderer(scene);
  return std::make_unique<CpuFrameRenderer>(scene, api);
}

std::unique_ptr<FrameRenderer> make_frame_renderer(const Scene& scene, ComputeDevice device, const Tracer& tracer) {
  if (device == ComputeDevice::cuda) return make_cuda_frame_renderer(scene);
  return std::make_unique<CpuFrameRenderer>(scene, tracer);
}

}  // namespace foveal
