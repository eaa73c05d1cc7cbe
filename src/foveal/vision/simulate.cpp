// foveal/vision/simulate.cpp — one time step of the vision simulation.
#include "foveal/vision/simulate.h"

#include "foveal/util/gaze_point.h"

#include "foveal/vision/thin_lens.h"

#include "foveal/vision/passes.h"

#include "foveal/util/error.h"
#include "foveal/util/sampling.h"
#include "foveal/util/timer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace foveal {

void validate(const SimulateParams& p) {
  if (p.width < 8 || p.height < 8 || p.width > 16384 || p.height > 16384)
    fail("size: the simulation needs at least 8x8 pixels, got {}x{}", p.width, p.height);
  validate(p.eye);
  if (p.fast_threshold < 1 || p.fast_threshold > 255) fail("fast_threshold: must be in [1, 255], got {}", p.fast_threshold);
  if (p.blink_every < 0) fail("blink_every: must be zero (never) or positive, got {}", p.blink_every);
  if (!(p.sharp_px > 0)) fail("sharp_px: must be positive, got {}", p.sharp_px);
  if (!(p.saccades.max_amplitude_deg > 0)) fail("saccade_max_deg: must be positive degrees, got {}", p.saccades.max_amplitude_deg);
  if (!(p.saccades.min_distance_deg >= 0)) fail("saccade_min_deg: must be zero or positive degrees, got {}", p.saccades.min_distance_deg);
  validate_starvation(p.starvation);  // (checked with the rest: a viewer outside vision mode builds no field)
}

SaccadeParams saccade_params_for(const EyeParams& eye, SaccadeParams base) {
  base.max_amplitude_deg *= 1.0 - 0.7 * eye.glaucoma;
  base.min_distance_deg *= 1.0 - 0.7 * eye.glaucoma;
  base.skip_probability = std::max(base.skip_probability, 0.5 * eye.glaucoma);
  return base;
}

VisionSimulation::VisionSimulation(const Tracer& tracer, const Scene& scene, const SimulateParams& params)
    : scene_(scene),
      params_((validate(params), params)),
      ppd_(0),
      field_(scene.bounds(), params.voxel > 0 ? params.voxel : default_voxel_size(scene.bounds()), params.starvation),
      saccades_(saccade_params_for(params.eye, params.saccades), params.height / 40.0, params.seed) {
  if (params_.impair.any()) impair_ = std::make_unique<ImpairmentPasses>(params_.impair);
  if (params_.cuda)
    passes_ = make_cuda_vision_passes(scene, field_, params_.blur);  // Error with the reason when no GPU answers
  else
    passes_ = make_cpu_vision_passes(tracer, scene, field_, params_.blur);
}

VisionSimulation::~VisionSimulation() = default;

const Image& VisionSimulation::color() const { return passes_->color(); }
const Image& VisionSimulation::perceived() const { return passes_->perceived(); }

nlohmann::json step_stats_json(const StepStats& s) {
  return {{"step", s.step},
          {"focus_px", {s.focus_px.x, s.focus_px.y}},
          {"focus_depth_m", std::isfinite(s.focus_depth_m) ? nlohmann::json(s.focus_depth_m) : nlohmann::json("inf")},
          {"focus_vergence_d", s.focus_vergence},
          {"sharp_fraction", s.sharp_fraction},
          {"blink", s.blink},
          {"skipped", s.skipped},
          {"camera_moved", s.camera_moved},
          {"corners", s.corners},
          {"time_ms",
           {{"trace", s.trace_ms},
            {"features", s.features_ms},
            {"sharpness", s.sharpness_ms},
            {"blur", s.blur_ms},
            {"impairments", s.impair.total_ms},
            {"total", s.total_ms}}}};
}

const std::vector<float>& VisionSimulation::coc_px() const { return passes_->coc_px(); }

bool VisionSimulation::blink_due(int step) {
  const bool due = (params_.blink_every > 0 && step > 1 && (step - 1) % params_.blink_every == 0) || blink_requested_;
  blink_requested_ = false;
  return due;
}

CocModel VisionSimulation::coc_model(const Camera& camera, glm::vec3 gaze_dir, double focus_vergence) const {
  CocModel m;
  m.axis = glm::normalize(camera.look - camera.eye);
  m.gaze_dir = gaze_dir;
  m.metres_per_unit = scene_.meters_per_unit;
  m.focus_vergence = static_cast<float>(focus_vergence);
  m.pupil_deg = static_cast<float>(glm::degrees(params_.eye.pupil_diameter_mm * 1e-3));
  m.penalty_per_deg = static_cast<float>(peripheral_penalty_per_deg(params_.eye));
  m.cylinder = static_cast<float>(params_.eye.cylinder_d);
  m.astigmatic = params_.eye.cylinder_d > 0;
  return m;
}

StepStats VisionSimulation::step(const Camera& camera, std::optional<glm::vec2> fixation) {
  if (fixation) check_gaze_point("fixation_px", fixation->x, fixation->y, params_.width, params_.height);
  const Timer total;
  StepStats s;
  s.step = static_cast<int>(++step_);
  const int w = params_.width, h = params_.height;
  VisionStepPasses& passes = *passes_;

  // 1. Ray-cast colour and depth
  passes.trace(camera, w, h, params_.ambient);

  // 2. Corners, recomputed when the camera moved; the next fixation
  ppd_ = camera_pixels_per_degree(camera, h);
  saccades_.set_pixels_per_degree(ppd_);
  s.camera_moved = !last_camera_ || !same_camera(*last_camera_, camera);
  const bool detect = s.camera_moved || params_.features_every_step;
  if (detect) {
    corners_ = passes.corners(params_.fast_threshold);
    if (s.camera_moved && last_camera_) saccades_.reset();  // a new view: no recent fixations in it
    last_camera_ = camera;
  }
  s.corners = corners_.size();
  const Timer choose;
  bool skipped = false;
  s.focus_px = fixation ? *fixation : saccades_.next(corners_, {w, h}, &skipped);
  s.skipped = skipped && !fixation;
  const double choose_ms = choose.ms();

  // 3. Accommodate to the fixated depth (along the optical axis: a thin lens focuses planes)
  const int fx = std::clamp(int(s.focus_px.x), 0, w - 1), fy = std::clamp(int(s.focus_px.y), 0, h - 1);
  glm::vec3 view(0.0f);
  const float depth = passes.depth_at(fx, fy, &view);
  const glm::vec3 axis = glm::normalize(camera.look - camera.eye);
  s.focus_depth_m = std::isfinite(depth) ? depth * glm::dot(view, axis) * scene_.meters_per_unit : INFINITY;
  s.focus_vergence = accommodate(params_.eye, s.focus_depth_m);
  if (blink_due(s.step)) {
    passes.blink();
    s.blink = true;
  }

  // 4. CoC per pixel and the field's update (glaucoma's skipped steps do not update it). The eye
  // sits at the camera: eccentricity is the angle between the camera rays through the pixel and
  // through the fixation.
  const glm::vec3 gaze_dir(CameraRays(camera, w, h)(s.focus_px.x, s.focus_px.y).dir);
  const size_t sharp =
      passes.sharpness(coc_model(camera, gaze_dir, s.focus_vergence), step_, !s.skipped, static_cast<float>(ppd_), params_.sharp_px);
  s.sharp_fraction = double(sharp) / (double(w) * h);

  // 5. Variable blur
  passes.blur(static_cast<float>(params_.eye.cylinder_axis_deg));

  // 6. Media, retina and colour, centred on the fixation
  if (impair_) {
    const Timer timer;
    s.impair = passes.impair(*impair_, CameraRetinotopy(camera, w, h, s.focus_px));
    s.impair.total_ms = timer.ms();  // with the retinotopy
  }

  const VisionPassTimes& t = passes.times();
  s.trace_ms = t.trace_ms;
  s.features_ms = (detect ? t.features_ms : 0.0) + choose_ms;  // the saccade's choice counts with the features
  s.sharpness_ms = t.sharpness_ms;
  s.blur_ms = t.blur_ms;
  s.total_ms = total.ms();
  return s;
}

}  // namespace foveal
