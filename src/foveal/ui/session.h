// foveal/ui/session.h — the viewer without its window: gaze in, progressive frames out.
//
// Once per displayed frame the window calls update(): the gaze source is polled and filtered into
// fixations (as `replay` does), and when the gaze the image depends on, the camera or a parameter
// has changed, a new render is handed to a background thread. That thread runs the same library
// functions as `render` and `simulate` in stages — a quarter-resolution frame with at most 16 AO
// rays first, then the full frame (the reference refines 16 → 64 → n_max rays) — and drops a
// stage as soon as its inputs are stale. update() takes the newest finished stage and draws the
// overlays for the current gaze on top, so input and overlays never wait for the renderer.
#pragma once

#include "foveal/gaze/fixation.h"
#include "foveal/gaze/source.h"
#include "foveal/impair/profile.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/render/realtime.h"
#include "foveal/render/render.h"
#include "foveal/ui/overlays.h"
#include "foveal/vision/simulate.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

// foveated AO; the full-frame reference; foveated | reference | difference side by side; the vision simulation.
enum class ViewMode { foveated, reference, side_by_side, vision };
const char* to_string(ViewMode mode);
ViewMode parse_view_mode(const std::string& name);  // throws Error for an unknown name

// Every parameter the panel edits.
struct ViewSettings {
  ViewMode mode = ViewMode::foveated;
  RenderParams render;          // size, display, n_max, n_min, γ, β, ellipse ratio, seed, AO distance, k_const
  SimulateParams vision;        // starvation, blink interval, … (its size is the render's; its eye and impairments resolve() sets)
  std::string eye = "healthy";  // the eye: presets joined with '+', or a profile .json
  EyeOverrides eye_overrides;   // the pupil and image distance the user set (they override the eye's)
  float diff_gain = 8;          // side by side: |foveated − reference| × this gain
  bool progressive = true;      // a cheap quarter-resolution frame before the full one
  bool cuda = false;            // frames and vision steps on the GPU (gpu::Renderer, gpu::VisionPasses)
  // Foveated mode: the real-time loop (render/realtime.h) makes a frame at every update() within
  // `frame_budget_ms`, the fovea refined first and placed at a saccade's predicted landing while
  // it flies, from the raw samples (instead of stages of whole frames for the filtered fixation)
  bool realtime = false;
  double frame_budget_ms = 10;
  bool predict = true;
  LandingParams landing;  // the saccade landing predictor's parameters (gaze/landing.h)
  // what each frame keeps free for the machine's pauses, and the share of the budget the
  // periphery's rays may run to (LoopSettings' margin_ms and periphery_share; unset: the loop's)
  std::optional<double> margin_ms;
  double periphery_share = kDefaultPeripheryShare;
  bool rays_ahead = true;               // LoopSettings::rays_ahead
  double min_scale = kDefaultMinScale;  // LoopSettings::min_scale: the smallest size the loop may render at
};
// The real-time loop's settings for the view (realtime)
LoopSettings view_loop_settings(const ViewSettings& settings);
// Resolve `eye` with `eye_overrides` into vision.eye and vision.impair (resolve_eye, the one rule for
// an eye) and check everything; throws Error.
void resolve(ViewSettings& settings);

// Where the gaze comes from.
struct GazeInput {
  std::unique_ptr<GazeSource> source;                                 // mouse, recording playback or live tracker; null: fixed gaze
  std::optional<glm::dvec2> fixed_px;                                 // no source: this render position (unset: the image centre)
  ScreenMapping mapping;                                              // source screen → render pixels
  Display display;                                                    // the source screen's physical size (angles for the filter)
  std::optional<FixationMethod> filter = kRecommendedFixationMethod;  // unset: every raw sample is the gaze
  FixationParams fixation;
};

// What the panel shows.
struct ViewStatus {
  std::string stage;       // "preview", "full", "reference 64 rays", "vision step 12", …
  bool converged = false;  // the last stage for the current inputs is shown
  double progress = 0;     // of the stage being rendered, 0..1
  double render_ms = 0;    // the shown stage's time
  double rays_per_s = 0;   // AO rays / AO pass time of the shown stage
  uint64_t ao_rays = 0;
  std::optional<glm::dvec2> gaze, fixation;  // render pixels
  glm::dvec2 render_gaze{0};                 // the gaze of the shown image
  std::string source;                        // gaze source name and state
  std::optional<StepStats> step;             // vision mode: the last step
};

class ViewSession {
 public:
  ViewSession(const Scene& scene, const Tracer& tracer, const Camera& camera, ViewSettings settings, GazeInput gaze);
  ~ViewSession();
  ViewSession(const ViewSession&) = delete;
  ViewSession& operator=(const ViewSession&) = delete;

  // Inputs, from the window's thread. A change restarts the render (the vision simulation starts
  // afresh when the eye or size changes; a new fixation or camera is its next step).
  void set_settings(ViewSettings settings);
  const ViewSettings& settings() const { return settings_; }
  void set_camera(const Camera& camera);
  const Camera& camera() const { return camera_; }
  // The mouse, when it is the gaze source (else null); positions in render pixels.
  MouseSource* mouse() const { return mouse_; }
  // Width of the shown image in render widths: 3 side by side, else 1.
  int panes() const { return settings_.mode == ViewMode::side_by_side ? 3 : 1; }

  // The refresh rate of the display the window is on, Hz (0: unknown). --realtime: a frame budget
  // longer than one refresh makes every frame miss refreshes, and the stage line says so.
  void set_display_refresh_hz(double hz) { display_refresh_hz_ = hz > 0 && std::isfinite(hz) ? hz : 0; }
  // Poll the gaze, start renders, take finished stages, draw the overlays. Call once per displayed frame.
  void update(const Overlays& overlays);
  const Rgba8& image() const { return shown_; }
  ViewStatus status() const;
  // Block until the current inputs' last stage is shown (for scripts and tests); false on timeout.
  bool wait_until_converged(double timeout_s, const Overlays& overlays);
  // The shown image as a PNG and, beside it (same name, .json), the parameters and the frame's stats.
  void save_screenshot(const std::string& png_path, nlohmann::json extra = {}) const;
  nlohmann::json stats_json() const;

 private:
  struct Worker;
  struct Shown;
  void request_if_changed();
  void compose(const Overlays& overlays);
  bool realtime() const { return settings_.realtime && settings_.mode == ViewMode::foveated; }
  void realtime_frame();

  const Scene& scene_;
  const Tracer& tracer_;
  Camera camera_;
  ViewSettings settings_;
  GazeInput gaze_;
  MouseSource* mouse_ = nullptr;
  std::optional<GazeGeometry> geometry_;
  std::optional<FixationTracker> tracker_;
  std::optional<glm::dvec2> raw_gaze_, fixation_;
  std::optional<glm::dvec2> step_fixation_;  // vision: the fixation of the last step
  std::optional<double> last_valid_s_;       // time of the last valid sample
  bool in_gap_ = false, blink_pending_ = false;
  std::vector<glm::dvec2> scanpath_;
  std::string settings_key_, view_key_;  // what the last request was for
  std::string region_key_, mark_key_;    // what the overlay layers show
  uint64_t generation_ = 0;
  std::unique_ptr<Worker> worker_;
  // --realtime: the loop, its renderer, and what it was made for
  std::unique_ptr<FrameRenderer> loop_renderer_;
  std::unique_ptr<RealtimeLoop> loop_;
  std::string loop_key_;
  double loop_t_ = 0;  // fixed gaze: the time pushed with it
  double display_refresh_hz_ = 0;
  std::unique_ptr<Shown> shown_state_;
  Rgba8 base_, layered_, shown_;  // the renders; with the region overlays; with the marks too
  bool base_dirty_ = true;
};

}  // namespace foveal
