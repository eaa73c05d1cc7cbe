// foveal/vision/passes.h — what one step of the vision simulation asks of a device.
//
// VisionSimulation (simulate.h) runs the same sequence of passes on either device: the CPU's
// (passes.cpp: Embree rays, cv::FAST, the field in pixel order, the blur with oneTBB) or the CUDA
// backend's, which implements this interface in cuda/ (make_cuda_vision_passes). The vision module
// never includes the backend: the factory below is its only contact with it.
#pragma once

#include "foveal/impair/impairments.h"
#include "foveal/scene/scene.h"
#include "foveal/trace/tracer.h"
#include "foveal/util/image.h"
#include "foveal/vision/blur.h"
#include "foveal/vision/coc.h"
#include "foveal/vision/features.h"
#include "foveal/vision/retinotopy.h"
#include "foveal/vision/sharpness.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace foveal {

// The last step's pass times, milliseconds (on the GPU from CUDA events; copies back on the host clock).
struct VisionPassTimes {
  double trace_ms = 0, features_ms = 0, sharpness_ms = 0, blur_ms = 0, download_ms = 0;
};

// Images, CoCs and timings stay with the passes; on the GPU they are copied back only when asked for.
class VisionStepPasses {
 public:
  virtual ~VisionStepPasses() = default;
  // Ray-cast colour and depth (Phong with a constant ambient term, textures where present)
  virtual void trace(const Camera& camera, int width, int height, float ambient) = 0;
  // FAST-9 corners of the traced image, non-maximum suppressed, by row then column
  virtual std::vector<Corner> corners(int threshold) = 0;
  // The hit distance along pixel (x, y)'s ray (infinity for the background), and the ray
  virtual float depth_at(int x, int y, glm::vec3* view) = 0;
  virtual void blink() = 0;
  // This step's CoC per pixel, the field's update (unless `update` is false), the blur's CoC in
  // pixels; returns how many pixels are sharp
  virtual size_t sharpness(const CocModel& model, uint32_t step, bool update, float ppd, float sharp_px) = 0;
  virtual void blur(float axis_deg) = 0;
  // An impaired eye's media, retina and colour (ImpairmentPasses::apply's passes, in its order) on
  // the blurred image, in place: perceived() is then the impaired image, centred on `where`'s
  // fixation (its grid is evaluated only where the retina is impaired).
  virtual ImpairTimes impair(const ImpairmentPasses& passes, const CameraRetinotopy& where) = 0;
  virtual const Image& color() = 0;
  virtual const Image& perceived() = 0;
  virtual const std::vector<float>& coc_px() = 0;
  // The last trace/corners/sharpness/blur's times, milliseconds
  virtual const VisionPassTimes& times() const = 0;
};

// The CPU's passes over `field` (kept by the caller, updated in place).
std::unique_ptr<VisionStepPasses> make_cpu_vision_passes(const Tracer& tracer, const Scene& scene, SharpnessField& field,
                                                         const BlurParams& blur);
// The CUDA backend's (cuda/gpu_vision_passes.cpp; the GPU keeps its own field with `field`'s grid and
// starvation). Throws Error with the reason when the backend is unavailable.
std::unique_ptr<VisionStepPasses> make_cuda_vision_passes(const Scene& scene, const SharpnessField& field, const BlurParams& blur);

}  // namespace foveal
