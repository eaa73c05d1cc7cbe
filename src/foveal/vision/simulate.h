// foveal/vision/simulate.h — the second paper's loop: ray-cast colour and depth → FAST corners →
// the next fixation → accommodation → per-pixel CoC → sharpness field → variable blur.
#pragma once

#include "foveal/impair/impairments.h"
#include "foveal/perception/eye.h"
#include "foveal/render/render.h"
#include "foveal/vision/blur.h"
#include "foveal/vision/coc.h"
#include "foveal/vision/features.h"
#include "foveal/vision/retinotopy.h"
#include "foveal/vision/sharpness.h"

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>

namespace foveal {

class VisionStepPasses;

// The eye sits at the camera: the camera's field of view, not a display, sets the visual angles.
struct SimulateParams {
  int width = 1024, height = 768;
  EyeParams eye;
  SaccadeParams saccades;            // glaucoma shortens and skips (see saccade_params_for)
  int fast_threshold = 20;           // cv::FAST threshold
  bool features_every_step = false;  // recompute the corners every step (the paper's timing), not only when the camera moves
  double starvation = 0.015;         // s: effective CoC grows by this fraction per step
  float voxel = 0;                   // cell edge, scene units; 0 = scene diagonal / 256
  int blink_every = 0;               // a blink (field reset) every this many steps; 0 = never
  float sharp_px = 1.0f;             // a pixel counts as sharp when its CoC is below this many pixels
  float ambient = 0.3f;              // constant Phong ambient factor of the colour image
  BlurParams blur;
  uint64_t seed = 1;
  bool cuda = false;  // run the passes on the GPU (make_cuda_vision_passes); the saccades stay on the CPU
  // After the optics: ocular media, the retina (metamorphopsia, field loss centred on the fixation),
  // colour vision (impair/impairments.h), on the device of the passes
  Impairments impair;
};
void validate(const SimulateParams& params);

// The saccade model's parameters for an eye: glaucoma of severity g shortens the maximum
// amplitude by up to 70 % and skips a step with probability 0.5·g.
SaccadeParams saccade_params_for(const EyeParams& eye, SaccadeParams base = {});

struct StepStats {
  int step = 0;               // 1-based
  glm::vec2 focus_px{0};      // fixation, render pixels
  double focus_depth_m = 0;   // distance of the fixated point (inf for the background)
  double focus_vergence = 0;  // what the eye accommodated to, dioptres
  bool skipped = false;       // glaucoma kept the last fixation (the field was not updated)
  bool blink = false;         // the field was reset before this step
  bool camera_moved = false;  // the corners were recomputed
  size_t corners = 0;
  double sharp_fraction = 0;  // pixels whose remembered CoC is below sharp_px
  double trace_ms = 0, features_ms = 0, sharpness_ms = 0, blur_ms = 0, total_ms = 0;
  ImpairTimes impair;  // the impairment passes (0 without any)
};

// One step's record as JSON (`simulate --stats`' "steps" entries, the Python step's stats): the
// fixation, depth and accommodation, blink, skip, corners, sharp share and stage times in ms.
nlohmann::json step_stats_json(const StepStats& s);

class VisionSimulation {
 public:
  // With params.cuda the scene is uploaded to the GPU (Error with the reason when none answers).
  VisionSimulation(const Tracer& tracer, const Scene& scene, const SimulateParams& params);
  ~VisionSimulation();
  // One step with this camera (the corners are recomputed when it differs from the last one's).
  // `fixation` replaces the simulated saccade (tracked gaze), in render pixels.
  StepStats step(const Camera& camera, std::optional<glm::vec2> fixation = std::nullopt);
  // The eye blinks before the next step (the field forgets), e.g. a tracker's blink.
  void blink_before_next_step() { blink_requested_ = true; }

  // On the GPU the images stay there until first asked for after a step.
  const Image& color() const;                // the sharp ray-cast image
  const Image& perceived() const;            // the blurred result (with the impairments, where there are any)
  const std::vector<float>& coc_px() const;  // per-pixel CoC diameter used for the blur
  const std::vector<Corner>& corners() const { return corners_; }
  // The field (on the CPU; with params.cuda the GPU keeps its own and this one stays empty).
  const SharpnessField& field() const { return field_; }
  bool on_gpu() const { return params_.cuda; }
  double pixels_per_degree() const { return ppd_; }  // the camera's, at the image centre (after a step)

 private:
  // The per-pixel CoC of this step: the camera's axis, the fixation's ray, the accommodation
  CocModel coc_model(const Camera& camera, glm::vec3 gaze_dir, double focus_vergence) const;

  const Scene& scene_;
  SimulateParams params_;
  double ppd_;
  SharpnessField field_;
  SaccadeModel saccades_;
  std::optional<Camera> last_camera_;
  std::vector<Corner> corners_;
  std::unique_ptr<VisionStepPasses> passes_;  // one step's passes on one device (vision/passes.h)
  std::unique_ptr<ImpairmentPasses> impair_;  // with params.impair.any()
  bool blink_due(int step);                   // a blink every blink_every steps, or one asked for (consumed)
  uint32_t step_ = 0;
  bool blink_requested_ = false;
};

}  // namespace foveal
