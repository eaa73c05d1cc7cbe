// foveal/cuda/gpu_vision_passes.cpp — the vision simulation's passes (vision/passes.h) on the GPU:
// gpu::VisionPasses behind the interface VisionSimulation runs its steps through.
#include "foveal/cuda/gpu.h"
#include "foveal/vision/passes.h"

#include <optional>

namespace foveal {

namespace {

// The passes on the GPU (gpu::VisionPasses keeps its own field); the images come back when first
// asked for after a step.
class GpuPasses final : public VisionStepPasses {
 public:
  GpuPasses(const Scene& scene, const SharpnessField& field, const BlurParams& blur) : gpu_(scene, field, blur) {}

  void trace(const Camera& camera, int width, int height, float ambient) override {
    gpu_.trace(camera, width, height, ambient);
    color_ = std::nullopt;  // each pass drops the copy of what it changed
  }
  std::vector<Corner> corners(int threshold) override { return gpu_.corners(threshold, true); }
  float depth_at(int x, int y, glm::vec3* view) override { return gpu_.depth_at(x, y, view); }
  void blink() override { gpu_.blink(); }
  size_t sharpness(const CocModel& model, uint32_t step, bool update, float ppd, float sharp_px) override {
    coc_ = std::nullopt;
    return gpu_.sharpness(model, step, update, ppd, sharp_px);
  }
  void blur(float axis_deg) override {
    gpu_.blur(axis_deg);
    perceived_ = std::nullopt;
  }
  ImpairTimes impair(const ImpairmentPasses& passes, const CameraRetinotopy& where) override {
    perceived_ = std::nullopt;
    return gpu_.impair(passes, where);
  }
  const Image& color() override { return color_ ? *color_ : color_.emplace(gpu_.color()); }
  const Image& perceived() override { return perceived_ ? *perceived_ : perceived_.emplace(gpu_.perceived()); }
  const std::vector<float>& coc_px() override { return coc_ ? *coc_ : coc_.emplace(gpu_.coc_px()); }
  const VisionPassTimes& times() const override { return gpu_.last_times(); }

 private:
  gpu::VisionPasses gpu_;
  std::optional<Image> color_, perceived_;
  std::optional<std::vector<float>> coc_;
};

}  // namespace

std::unique_ptr<VisionStepPasses> make_cuda_vision_passes(const Scene& scene, const SharpnessField& field, const BlurParams& blur) {
  return std::make_unique<GpuPasses>(scene, field, blur);
}

}  // namespace foveal
