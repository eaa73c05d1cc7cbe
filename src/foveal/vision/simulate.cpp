// foveal/vision/simulate.cpp — one time step of the vision simulation.
#include "foveal/vision/simulate.h"

#include "foveal/vision/thin_lens.h"

#include "foveal/cuda/gpu.h"

#include "foveal/util/error.h"
#include "foveal/util/sampling.h"
#include "foveal/util/timer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace foveal {

void validate(const SimulateParams& p) {
  if (p.width < 8 || p.height < 8 || p.width > 16384 || p.height > 16384)
    fail("--size: the simulation needs at least 8x8 pixels, got {}x{}", p.width, p.height);
  validate(p.eye);
  if (p.fast_threshold < 1 || p.fast_threshold > 255) fail("--fast-threshold: must be in [1, 255], got {}", p.fast_threshold);
  if (p.blink_every < 0) fail("--blink-every: must be zero (never) or positive, got {}", p.blink_every);
  if (!(p.sharp_px > 0)) fail("--sharp-px: must be positive, got {}", p.sharp_px);
  if (!(p.saccades.max_amplitude_deg > 0)) fail("--saccade-max: must be positive degrees, got {}", p.saccades.max_amplitude_deg);
  if (!(p.saccades.min_distance_deg >= 0)) fail("--saccade-min: must be zero or positive degrees, got {}", p.saccades.min_distance_deg);
}

SaccadeParams saccade_params_for(const EyeParams& eye, SaccadeParams base) {
  base.max_amplitude_deg *= 1.0 - 0.7 * eye.glaucoma;
  base.min_distance_deg *= 1.0 - 0.7 * eye.glaucoma;
  base.skip_probability = std::max(base.skip_probability, 0.5 * eye.glaucoma);
  return base;
}

namespace {

bool same_camera(const Camera& a, const Camera& b) {
  return a.eye == b.eye && a.look == b.look && a.up == b.up && a.fov_deg == b.fov_deg;
}

}  // namespace

VisionSimulation::VisionSimulation(const Tracer& tracer, const Scene& scene, const SimulateParams& params)
    : tracer_(tracer),
      scene_(scene),
      params_((validate(params), params)),
      ppd_(0),
      epsilon_(surface_epsilon(scene.bounds())),
      field_(scene.bounds(), params.voxel > 0 ? params.voxel : default_voxel_size(scene.bounds()), params.starvation),
      saccades_(saccade_params_for(params.eye, params.saccades), params.height / 40.0, params.seed) {
  if (params_.cuda) gpu_ = std::make_unique<gpu::VisionPasses>(scene, field_, params_.blur);
}

VisionSimulation::~VisionSimulation() = default;

const Image& VisionSimulation::color() const {
  if (color_stale_) color_ = gpu_->color();
  color_stale_ = false;
  return color_;
}

const Image& VisionSimulation::perceived() const {
  if (perceived_stale_) perceived_ = gpu_->perceived();
  perceived_stale_ = false;
  return perceived_;
}

const std::vector<float>& VisionSimulation::coc_px() const {
  if (coc_stale_) coc_ = gpu_->coc_px();
  coc_stale_ = false;
  return coc_;
}

bool VisionSimulation::blink_due(int step) {
  const bool due = (params_.blink_every > 0 && step > 1 && (step - 1) % params_.blink_every == 0) || blink_requested_;
  blink_requested_ = false;
  return due;
}

// The same step with the passes on the GPU (gpu::VisionPasses): only the corners, the fixated
// pixel's depth and the sharp count come back; the images when asked for.
StepStats VisionSimulation::gpu_step(const Camera& camera, std::optional<glm::vec2> fixation) {
  const Timer total;
  StepStats s;
  s.step = static_cast<int>(++step_);
  const int w = params_.width, h = params_.height;
  gpu_->trace(camera, w, h, params_.ambient);
  ppd_ = camera_pixels_per_degree(camera, h);
  saccades_.set_pixels_per_degree(ppd_);
  s.camera_moved = !last_camera_ || !same_camera(*last_camera_, camera);
  if (s.camera_moved || params_.features_every_step) {
    corners_ = gpu_->corners(params_.fast_threshold, true);
    if (s.camera_moved && last_camera_) saccades_.reset();
    last_camera_ = camera;
  }
  s.corners = corners_.size();
  bool skipped = false;
  const Timer choose;
  s.focus_px = fixation ? *fixation : saccades_.next(corners_, {w, h}, &skipped);
  s.skipped = skipped && !fixation;
  const double choose_ms = choose.ms();
  const int fx = std::clamp(int(s.focus_px.x), 0, w - 1), fy = std::clamp(int(s.focus_px.y), 0, h - 1);
  glm::vec3 view(0.0f);
  const float depth = gpu_->depth_at(fx, fy, &view);
  const glm::vec3 axis = glm::normalize(camera.look - camera.eye);
  s.focus_depth_m = std::isfinite(depth) ? depth * glm::dot(view, axis) * scene_.meters_per_unit : INFINITY;
  s.focus_vergence = accommodate(params_.eye, s.focus_depth_m);
  if (blink_due(s.step)) {
    field_.blink();
    gpu_->blink();
    s.blink = true;
  }
  const glm::vec3 gaze_dir(CameraRays(camera, w, h)(s.focus_px.x, s.focus_px.y).dir);
  const size_t sharp = gpu_->sharpness(coc_model(camera, gaze_dir, s.focus_vergence), step_, !s.skipped,
                                       static_cast<float>(ppd_), params_.sharp_px);
  s.sharp_fraction = double(sharp) / (double(w) * h);
  gpu_->blur(static_cast<float>(params_.eye.cylinder_axis_deg));
  color_stale_ = perceived_stale_ = coc_stale_ = true;
  // The passes' GPU times (the saccade choice on the CPU counts with the features)
  const gpu::VisionPassTimes& t = gpu_->last_times();
  s.trace_ms = t.trace_ms;
  s.features_ms = (s.camera_moved || params_.features_every_step ? t.features_ms : 0.0) + choose_ms;
  s.sharpness_ms = t.sharpness_ms;
  s.blur_ms = t.blur_ms;
  s.total_ms = total.ms();
  return s;
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
  if (gpu_) return gpu_step(camera, fixation);
  const Timer total;
  StepStats s;
  s.step = static_cast<int>(++step_);
  const int w = params_.width, h = params_.height;
  const size_t n = size_t(w) * h;

  // 1. Ray-cast colour and depth (Phong with a constant ambient term, textures where present)
  Timer t;
  gbuffer_ = trace_primary(tracer_, scene_, camera, w, h);
  color_ = shade_constant_ambient(tracer_, scene_, camera, gbuffer_, params_.ambient, epsilon_);
  s.trace_ms = t.ms();

  // 2. Corners, recomputed when the camera moved; the next fixation
  t.reset();
  ppd_ = camera_pixels_per_degree(camera, h);
  saccades_.set_pixels_per_degree(ppd_);
  s.camera_moved = !last_camera_ || !same_camera(*last_camera_, camera);
  if (s.camera_moved || params_.features_every_step) {
    corners_ = detect_corners(color_, params_.fast_threshold, true);
    if (s.camera_moved && last_camera_) saccades_.reset();  // a new view: no recent fixations in it
    last_camera_ = camera;
  }
  s.corners = corners_.size();
  bool skipped = false;
  s.focus_px = fixation ? *fixation : saccades_.next(corners_, {w, h}, &skipped);
  s.skipped = skipped && !fixation;
  s.features_ms = t.ms();

  // 3. Accommodate to the fixated depth, CoC per pixel, update the field
  t.reset();
  const int fx = std::clamp(int(s.focus_px.x), 0, w - 1), fy = std::clamp(int(s.focus_px.y), 0, h - 1);
  const size_t fi = size_t(fy) * w + fx;
  const glm::vec3 axis = glm::normalize(camera.look - camera.eye);
  s.focus_depth_m = gbuffer_.hit(fi) ? gbuffer_.depth[fi] * glm::dot(gbuffer_.view[fi], axis) * scene_.meters_per_unit : INFINITY;
  s.focus_vergence = accommodate(params_.eye, s.focus_depth_m);
  if (blink_due(s.step)) {
    field_.blink();
    s.blink = true;
  }
  // The eye sits at the camera: eccentricity is the angle between the camera rays through the
  // pixel and through the fixation; distances are along the optical axis (a thin lens focuses planes)
  const CameraRays rays(camera, w, h);
  const glm::vec3 gaze_dir(rays(s.focus_px.x, s.focus_px.y).dir);
  const bool astigmatic = params_.eye.cylinder_d > 0;
  if (astigmatic) {
    shape_.scale.resize(n);
    shape_.axis_deg = static_cast<float>(params_.eye.cylinder_axis_deg);
  }
  const CocModel model = coc_model(camera, gaze_dir, s.focus_vergence);
  std::vector<float> now_deg(n);  // this step's CoC (the ellipse's larger diameter), degrees
  std::vector<int64_t> cells(n);  // each pixel's field cell (−1: background)
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const bool hit = gbuffer_.hit(i);
        cells[i] = hit ? field_.cell(gbuffer_.position[i]) : -1;
        const PixelCoc c = model(hit, gbuffer_.depth[i], gbuffer_.view[i]);
        now_deg[i] = c.major_deg;
        if (astigmatic) shape_.scale[i] = c.scale;
      }
  });
  // Pixels share cells, so the update runs in pixel order on one thread (deterministic)
  if (!s.skipped)  // glaucoma's skipped steps do not update the field
    for (size_t i = 0; i < n; ++i) field_.update(cells[i], now_deg[i], step_);
  // The blur's CoC: the field's memory where there is geometry, this step's CoC for the background
  coc_.resize(n);
  const float ppd = static_cast<float>(ppd_);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) coc_[i] = (cells[i] >= 0 ? field_.effective(cells[i], step_) : now_deg[i]) * ppd;
  });
  s.sharp_fraction = double(std::count_if(coc_.begin(), coc_.end(), [&](float c) { return c < params_.sharp_px; })) / n;
  s.sharpness_ms = t.ms();

  // 4. Variable blur
  t.reset();
  perceived_ = variable_blur(color_, coc_, params_.blur, astigmatic ? &shape_ : nullptr);
  s.blur_ms = t.ms();
  s.total_ms = total.ms();
  return s;
}

}  // namespace foveal
