// foveal/vision/passes.cpp — the vision simulation's passes on the CPU.
#include "foveal/vision/passes.h"

#include "foveal/render/render.h"

#include "foveal/util/timer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace foveal {

namespace {

// The passes on the CPU: Embree rays, cv::FAST, the field in pixel order, the blur with oneTBB.
class CpuPasses final : public VisionStepPasses {
 public:
  CpuPasses(const Tracer& tracer, const Scene& scene, SharpnessField& field, const BlurParams& blur)
      : tracer_(tracer), scene_(scene), field_(field), blur_(blur), epsilon_(surface_epsilon(scene.bounds())) {}

  void trace(const Camera& camera, int width, int height, float ambient) override {
    const Timer t;
    trace_primary_shaded(tracer_, scene_, camera, width, height, ambient, epsilon_, gbuffer_, color_);
    times_ = {};
    times_.trace_ms = t.ms();
  }

  std::vector<Corner> corners(int threshold) override {
    const Timer t;
    std::vector<Corner> found = detect_corners(color_, threshold, true);
    times_.features_ms = t.ms();
    return found;
  }

  float depth_at(int x, int y, glm::vec3* view) override {
    const size_t i = size_t(y) * gbuffer_.width + x;
    if (view) *view = gbuffer_.view[i];
    return gbuffer_.hit(i) ? gbuffer_.depth[i] : INFINITY;
  }

  void blink() override { field_.blink(); }

  size_t sharpness(const CocModel& model, uint32_t step, bool update, float ppd, float sharp_px) override {
    const Timer t;
    const int w = gbuffer_.width, h = gbuffer_.height;
    const size_t n = size_t(w) * h;
    astigmatic_ = model.astigmatic;
    if (astigmatic_) shape_.scale.resize(n);
    now_deg_.resize(n);  // this step's CoC (the ellipse's larger diameter), degrees
    cells_.resize(n);    // each pixel's field cell (−1: background)
    tbb::parallel_for(tbb::blocked_range<int>(0, h, 8), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < w; ++x) {
          const size_t i = size_t(y) * w + x;
          const bool hit = gbuffer_.hit(i);
          cells_[i] = hit ? field_.cell(gbuffer_.position[i]) : -1;
          const PixelCoc c = model(hit, gbuffer_.depth[i], gbuffer_.view[i]);
          now_deg_[i] = c.major_deg;
          if (astigmatic_) shape_.scale[i] = c.scale;
        }
    });
    // Pixels share cells, so the update runs in pixel order on one thread (deterministic)
    if (update)
      for (size_t i = 0; i < n; ++i) field_.update(cells_[i], now_deg_[i], step);
    // The blur's CoC: the field's memory where there is geometry, this step's CoC for the background
    coc_.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) coc_[i] = (cells_[i] >= 0 ? field_.effective(cells_[i], step) : now_deg_[i]) * ppd;
    });
    const size_t sharp = std::count_if(coc_.begin(), coc_.end(), [&](float c) { return c < sharp_px; });
    times_.sharpness_ms = t.ms();
    return sharp;
  }

  void blur(float axis_deg) override {
    const Timer t;
    shape_.axis_deg = axis_deg;
    perceived_ = variable_blur(color_, coc_, blur_, astigmatic_ ? &shape_ : nullptr);
    times_.blur_ms = t.ms();
  }

  ImpairTimes impair(const ImpairmentPasses& passes, const CameraRetinotopy& where) override {
    return passes.apply(perceived_, expand(passes.needs_retinotopy() ? where.grid() : where.sizes()));
  }

  const Image& color() override { return color_; }
  const Image& perceived() override { return perceived_; }
  const std::vector<float>& coc_px() override { return coc_; }
  const VisionPassTimes& times() const override { return times_; }

 private:
  const Tracer& tracer_;
  const Scene& scene_;
  SharpnessField& field_;
  BlurParams blur_;
  float epsilon_;
  GBuffer gbuffer_;
  Image color_, perceived_;
  std::vector<float> now_deg_, coc_;
  std::vector<int64_t> cells_;
  CocShape shape_;  // astigmatism: this step's ellipse per pixel
  bool astigmatic_ = false;
  VisionPassTimes times_;
};

}  // namespace

std::unique_ptr<VisionStepPasses> make_cpu_vision_passes(const Tracer& tracer, const Scene& scene, SharpnessField& field,
                                                         const BlurParams& blur) {
  return std::make_unique<CpuPasses>(tracer, scene, field, blur);
}

}  // namespace foveal
