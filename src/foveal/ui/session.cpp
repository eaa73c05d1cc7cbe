// foveal/ui/session.cpp — see session.h.
#include "foveal/ui/session.h"

#include "foveal/gaze/steps.h"
#include "foveal/impair/profile.h"
#include "foveal/io/image_io.h"
#include "foveal/render/outputs.h"
#include "foveal/perception/eye.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/util/error.h"
#include "foveal/util/timer.h"

#include <fmt/core.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>

namespace foveal {

const char* to_string(ViewMode mode) {
  switch (mode) {
    case ViewMode::foveated:
      return "foveated";
    case ViewMode::reference:
      return "reference";
    case ViewMode::side_by_side:
      return "side-by-side";
    case ViewMode::vision:
      return "vision";
  }
  return "?";
}

ViewMode parse_view_mode(const std::string& name) {
  for (ViewMode m : {ViewMode::foveated, ViewMode::reference, ViewMode::side_by_side, ViewMode::vision})
    if (name == to_string(m)) return m;
  fail("mode: unknown view mode '{}' (foveated, reference, side-by-side or vision)", name);
}

void resolve(ViewSettings& s) {
  validate(s.render);
  const EyeSpec spec = resolve_eye(s.eye, s.eye_overrides);  // optics and impairments (presets or a profile)
  s.vision.eye = spec.eye;
  s.vision.impair = spec.impair;
  s.vision.width = s.render.width;
  s.vision.height = s.render.height;
  validate(s.vision);
  if (!(s.diff_gain > 0)) fail("diff_gain: must be positive, got {}", s.diff_gain);
  if (!(s.frame_budget_ms > 0 && s.frame_budget_ms <= 1000)) fail("frame_budget_ms: must be in (0, 1000] ms, got {}", s.frame_budget_ms);
  validate(view_loop_settings(s));  // (whatever the mode, as above)
}

LoopSettings view_loop_settings(const ViewSettings& s) {
  LoopSettings ls;
  ls.budget_ms = s.frame_budget_ms;
  ls.predict = s.predict;
  ls.landing = s.landing;
  ls.margin_ms = s.margin_ms;
  ls.periphery_share = s.periphery_share;
  ls.rays_ahead = s.rays_ahead;
  ls.min_scale = s.min_scale;
  return ls;
}

namespace {

struct Cancelled {};

nlohmann::json settings_json(const ViewSettings& s) {
  const RenderParams& r = s.render;
  const EyeParams& e = s.vision.eye;
  return {{"mode", to_string(s.mode)},
          {"realtime", s.realtime ? nlohmann::json{{"frame_budget_ms", s.frame_budget_ms},
                                                   {"predict", s.predict},
                                                   {"margin_ms", loop_margin_ms(s.frame_budget_ms, s.margin_ms)},
                                                   {"periphery_share", s.periphery_share},
                                                   {"rays_ahead", s.rays_ahead},
                                                   {"min_scale", s.min_scale}}
                                  : nlohmann::json(false)},
          {"width", r.width},
          {"height", r.height},
          {"display",
           {{"width_cm", r.display.width_cm},
            {"height_cm", r.display.height_cm},
            {"distance_cm", r.display.distance_cm},
            {"res_x", r.display.res_x},
            {"res_y", r.display.res_y}}},
          {"foveation",
           {{"max_rays", r.foveation.max_rays},
            {"min_rays", r.foveation.min_rays},
            {"gamma", r.foveation.gamma},
            {"beta", r.foveation.beta},
            {"ellipse_ratio", r.foveation.ellipse_ratio}}},
          {"seed", r.seed},
          {"ao_distance",
           r.ao_distance ? nlohmann::json(std::isfinite(*r.ao_distance) ? nlohmann::json(*r.ao_distance) : "inf") : nlohmann::json("auto")},
          {"ambient_constant", r.ambient_constant ? nlohmann::json(*r.ambient_constant) : nlohmann::json("auto")},
          {"eye",
           {{"preset", s.eye},
            {"pupil_mm", e.pupil_diameter_mm},
            {"image_distance_mm", e.image_distance_mm},
            {"starvation", s.vision.starvation},
            {"blink_every", s.vision.blink_every},
            {"voxel", s.vision.voxel},
            {"sharp_px", s.vision.sharp_px},
            {"seed", s.vision.seed}}},
          {"diff_gain", s.diff_gain},
          {"progressive", s.progressive},
          {"device", s.cuda ? "cuda" : "cpu"}};
}

nlohmann::json camera_json(const Camera& c) {
  return {{"eye", {c.eye.x, c.eye.y, c.eye.z}},
          {"look", {c.look.x, c.look.y, c.look.z}},
          {"up", {c.up.x, c.up.y, c.up.z}},
          {"fov_deg", c.fov_deg}};
}

nlohmann::json point_json(const std::optional<glm::dvec2>& p) { return p ? nlohmann::json{p->x, p->y} : nlohmann::json(nullptr); }

// Nearest-neighbour enlargement of a preview to the full size.
Image enlarge(const Image& small, int width, int height) {
  if (small.width == width && small.height == height) return small;
  Image out(width, height, small.channels);
  tbb::parallel_for(0, height, [&](int y) {
    const int sy = std::min(small.height - 1, y * small.height / height);
    for (int x = 0; x < width; ++x) {
      const int sx = std::min(small.width - 1, x * small.width / width);
      for (int c = 0; c < small.channels; ++c) out.at(x, y, c) = small.at(sx, sy, c);
    }
  });
  return out;
}

// |a − b| × gain, clamped to 1.
Image difference(const Image& a, const Image& b, float gain) {
  Image out(a.width, a.height, a.channels);
  for (size_t i = 0; i < a.pixels.size(); ++i) out.pixels[i] = std::min(1.0f, std::abs(a.pixels[i] - b.pixels[i]) * gain);
  return out;
}

}  // namespace

// One render request and what the background thread makes of it.
struct Request {
  uint64_t generation = 0;
  ViewSettings settings;
  Camera camera;
  glm::dvec2 gaze{0};
  bool restart_vision = false;
  bool blink = false;  // vision: the eye blinked since the last step
};

struct Result {
  uint64_t generation = 0;
  bool last = false;  // the request's final stage
  std::string stage;
  Image fov, ref;          // AO modes: the foveated and reference panes (empty: not yet)
  Image perceived;         // vision mode
  std::vector<float> coc;  // vision mode: per-pixel remembered CoC
  std::optional<StepStats> step;
  FrameStats stats;  // the stage's frame (side by side: the reference once it has one)
  glm::dvec2 gaze{0};
  std::string error;
};

struct ViewSession::Worker {
  const Scene& scene;
  const Tracer& tracer;
  std::mutex mutex;
  std::condition_variable wake;
  std::optional<Request> pending;  // guarded by mutex
  std::optional<Result> finished;  // guarded by mutex
  bool stop = false;               // guarded by mutex
  std::atomic<uint64_t> wanted{0};
  std::atomic<double> progress{0};
  std::unique_ptr<VisionSimulation> sim;  // the worker's own
  // The frames' renderer on the settings' device, made on first use; with --temporal it keeps the
  // AO rays of the full-size foveated frames so far
  std::unique_ptr<FrameRenderer> renderer;
  std::thread thread;

  Worker(const Scene& s, const Tracer& t) : scene(s), tracer(t), thread([this] { loop(); }) {}
  ~Worker() {
    {
      const std::lock_guard lock(mutex);
      stop = true;
    }
    wanted = ~uint64_t(0);
    wake.notify_all();
    thread.join();
  }

  void submit(Request r) {
    wanted = r.generation;
    {
      const std::lock_guard lock(mutex);
      if (pending && pending->blink) r.blink = true;  // a replaced step's blink still happened
      pending = std::move(r);
    }
    wake.notify_all();
  }

  std::optional<Result> take() {
    const std::lock_guard lock(mutex);
    std::optional<Result> r = std::move(finished);
    finished.reset();
    return r;
  }

  void publish(Result r) {
    const std::lock_guard lock(mutex);
    finished = std::move(r);
  }

  void loop() {
    for (;;) {
      Request r;
      {
        std::unique_lock lock(mutex);
        wake.wait(lock, [&] { return stop || pending.has_value(); });
        if (stop) return;
        r = std::move(*pending);
        pending.reset();
      }
      try {
        run(r);
      } catch (const Cancelled&) {
      } catch (const std::exception& e) {
        Result failed;
        failed.generation = r.generation;
        failed.last = true;
        failed.stage = "error";
        failed.error = e.what();
        publish(std::move(failed));
      }
    }
  }

  void check(uint64_t generation) const {
    if (wanted.load() != generation) throw Cancelled{};
  }

  // One frame of the AO renderer at `1/scale` of the size and at most `rays` AO rays.
  Frame render(const Request& r, RenderMode mode, int scale, int rays) {
    RenderParams p = r.settings.render;
    p.mode = mode;
    p.width = std::max(1, p.width / scale);
    p.height = std::max(1, p.height / scale);
    p.gaze_px = r.gaze * (static_cast<double>(p.width) / r.settings.render.width);
    p.foveation.max_rays = std::min(p.foveation.max_rays, rays);
    p.foveation.min_rays = std::min(p.foveation.min_rays, p.foveation.max_rays);
    progress = 0;
    // --temporal: the full-size foveated frame builds on the history of the ones before (any gaze
    // or camera; reprojection keeps what still applies); previews and references start afresh
    const bool final_foveated = mode == RenderMode::foveated && scale == 1 && rays == r.settings.render.foveation.max_rays;
    if (!renderer) renderer = make_frame_renderer(scene, r.settings.cuda ? ComputeDevice::cuda : ComputeDevice::cpu, tracer);
    FrameOptions options;
    options.outputs = FrameOutputs::colour_only();
    options.use_history = final_foveated;
    // The CPU reports the AO pass (and is cancelled inside it); a GPU frame takes milliseconds and
    // is cancelled between stages
    options.progress = [&](double fraction) {
      progress = fraction;
      check(r.generation);
    };
    Frame f = renderer->render(r.camera, p, options);
    check(r.generation);
    return f;
  }

  void run(const Request& r) {
    const ViewSettings& s = r.settings;
    const int w = s.render.width, h = s.render.height, n_max = s.render.foveation.max_rays;
    Result out;
    out.generation = r.generation;
    out.gaze = r.gaze;
    if (s.mode == ViewMode::vision) {
      if (!sim || r.restart_vision) {
        SimulateParams vision = s.vision;
        vision.cuda = s.cuda;
        sim = std::make_unique<VisionSimulation>(tracer, scene, vision);
      }
      if (r.blink) sim->blink_before_next_step();
      const StepStats step = sim->step(r.camera, glm::vec2(r.gaze));
      out.last = true;
      out.stage = fmt::format("vision step {}", step.step);
      out.perceived = sim->perceived();
      out.coc = sim->coc_px();
      out.step = step;
      return publish(std::move(out));
    }
    // The stages: (mode, scale, rays) in order; the last is the frame `render` makes
    struct Stage {
      RenderMode mode;
      int scale, rays;
      std::string name;
    };
    std::vector<Stage> stages;
    auto add = [&](RenderMode mode, bool reference) {
      const std::string what = reference ? "reference" : "foveated";
      if (s.progressive && (w >= 64 && h >= 64)) stages.push_back({mode, 4, 16, what + " preview"});
      if (reference)
        for (int rays : {16, 64})
          if (rays < n_max) stages.push_back({mode, 1, rays, fmt::format("reference {} rays", rays)});
      stages.push_back({mode, 1, n_max, what});
    };
    if (s.mode != ViewMode::reference) add(RenderMode::foveated, false);
    if (s.mode != ViewMode::foveated) add(RenderMode::full, true);
    for (size_t k = 0; k < stages.size(); ++k) {
      const Stage& st = stages[k];
      check(r.generation);
      Frame f = render(r, st.mode, st.scale, st.rays);
      Image shown = st.scale > 1 ? enlarge(f.color, w, h) : std::move(f.color);
      (st.mode == RenderMode::foveated ? out.fov : out.ref) = std::move(shown);
      out.stats = f.stats;
      out.stage = st.name;
      out.last = k + 1 == stages.size();
      Result copy = out;
      publish(std::move(copy));
    }
  }
};

struct ViewSession::Shown {
  Result result;
  bool any = false;
  bool converged = false;
};

ViewSession::ViewSession(const Scene& scene, const Tracer& tracer, const Camera& camera, ViewSettings settings, GazeInput gaze)
    : scene_(scene),
      tracer_(tracer),
      camera_(camera),
      settings_(std::move(settings)),
      gaze_(std::move(gaze)),
      shown_state_(std::make_unique<Shown>()) {
  resolve(settings_);
  if (gaze_.source) {
    mouse_ = dynamic_cast<MouseSource*>(gaze_.source.get());
    geometry_.emplace(gaze_.display, gaze_.source->screen_px());
    if (gaze_.filter) tracker_.emplace(*gaze_.filter, gaze_.fixation, *geometry_);
  }
  worker_ = std::make_unique<Worker>(scene_, tracer_);
}

ViewSession::~ViewSession() = default;

void ViewSession::set_settings(ViewSettings settings) {
  resolve(settings);
  settings_ = std::move(settings);
}

void ViewSession::set_camera(const Camera& camera) { camera_ = camera; }

void ViewSession::request_if_changed() {
  const glm::dvec2 centre(settings_.render.width * 0.5, settings_.render.height * 0.5);
  glm::dvec2 gaze = fixation_.value_or(centre);
  if (settings_.mode == ViewMode::vision) {
    // A step per new fixation: the filter refines a fixation's centre as its samples arrive, and
    // a move of less than 1° is the same fixation
    const double px_per_deg = pixels_per_degree(settings_.render.display) * settings_.render.width / settings_.render.display.res_x;
    if (!step_fixation_ || glm::length(gaze - *step_fixation_) > px_per_deg) step_fixation_ = gaze;
    gaze = *step_fixation_;
  }
  // What the image depends on: the settings, the camera, and (but for the reference) the gaze
  const std::string settings_key = settings_json(settings_).dump();
  const std::string view_key =
      camera_json(camera_).dump() + (settings_.mode != ViewMode::reference ? fmt::format("|{},{}", gaze.x, gaze.y) : "");
  if (settings_key == settings_key_ && view_key == view_key_) return;
  // The vision simulation starts afresh when anything but the camera and the fixation changed
  const bool restart = settings_key != settings_key_;
  settings_key_ = settings_key;
  view_key_ = view_key;
  Request r;
  r.generation = ++generation_;
  r.settings = settings_;
  r.camera = camera_;
  r.gaze = gaze;
  r.restart_vision = restart;
  if (settings_.mode == ViewMode::vision && blink_pending_) {
    r.blink = true;
    blink_pending_ = false;
  }
  shown_state_->converged = false;
  worker_->submit(std::move(r));
}

void ViewSession::update(const Overlays& overlays) {
  // Gaze: poll and filter, as replay does
  if (gaze_.source) {
    std::vector<GazeSample> samples;
    gaze_.source->poll(samples);
    for (const GazeSample& s : samples) {
      if (tracker_) tracker_->push(s);
      if (loop_ && realtime()) loop_->push_gaze(s.t_s, s.valid ? std::optional<glm::dvec2>(gaze_.mapping.to_render(s.px)) : std::nullopt);
      if (s.valid) {
        raw_gaze_ = gaze_.mapping.to_render(s.px);
        // A tracker's lost samples for a blink's duration (not the cursor leaving the image): the field forgets
        if (!mouse_ && in_gap_ && last_valid_s_ && blink_gap(*last_valid_s_, s.t_s)) blink_pending_ = true;
        last_valid_s_ = s.t_s;
      }
      in_gap_ = !s.valid;
    }
    if (!samples.empty() && !samples.back().valid) raw_gaze_.reset();
    if (tracker_) {
      if (const auto f = tracker_->frame_gaze()) fixation_ = gaze_.mapping.to_render(*f);
    } else if (raw_gaze_) {
      fixation_ = raw_gaze_;
    }
  } else {
    raw_gaze_ = fixation_ = gaze_.fixed_px.value_or(glm::dvec2(settings_.render.width * 0.5, settings_.render.height * 0.5));
  }
  if (fixation_ && (scanpath_.empty() || glm::length(scanpath_.back() - *fixation_) > 0.5)) {
    scanpath_.push_back(*fixation_);
    if (scanpath_.size() > 40) scanpath_.erase(scanpath_.begin());
  }
  if (realtime()) {
    realtime_frame();
    tbb::this_task_arena::isolate([&] { compose(overlays); });
    return;
  }
  request_if_changed();
  // The newest finished stage of the newest request
  if (std::optional<Result> r = worker_->take()) {
    Shown& sh = *shown_state_;
    // A stale request's stage is still the best image there is until the new one's first stage
    sh.result = std::move(*r);
    sh.any = true;
    sh.converged = sh.result.generation == generation_ && sh.result.last;
    base_dirty_ = true;
  }
  // Isolated: this thread's parallel loops must not pick up the renderer's tiles while they wait
  tbb::this_task_arena::isolate([&] { compose(overlays); });
}

// --realtime: the loop's frame for this update, made within the budget on this thread.
void ViewSession::realtime_frame() {
  const std::string key = settings_json(settings_).dump();
  if (!loop_ || key != loop_key_) {
    loop_.reset();
    loop_renderer_ = make_frame_renderer(scene_, settings_.cuda ? ComputeDevice::cuda : ComputeDevice::cpu, tracer_);
    loop_ = std::make_unique<RealtimeLoop>(*loop_renderer_, scene_, settings_.render, view_loop_settings(settings_));
    loop_key_ = key;
    if (raw_gaze_) loop_->push_gaze(loop_t_ += 1e-3, raw_gaze_);
  }
  if (!gaze_.source && raw_gaze_) loop_->push_gaze(loop_t_ += 1e-3, raw_gaze_);  // a fixed gaze
  Shown& sh = *shown_state_;
  Result& r = sh.result;
  loop_->recycle(std::move(r.fov));  // the image shown before: this frame is composed into it (a fresh one costs its page faults)
  LoopFrame f = loop_->frame(camera_);
  r = Result{};
  r.generation = generation_;
  r.last = f.fovea_done;
  const std::string gaze_note = loop_->gaze_note();  // samples too slow to predict from, a clock that went back
  const double refresh_ms = display_refresh_hz_ > 0 ? 1000 / display_refresh_hz_ : 0;
  const std::string budget_note =
      refresh_ms > 0 && settings_.frame_budget_ms > refresh_ms
          ? fmt::format(
                "; the frame budget of {:g} ms is longer than the display's refresh ({:.3g} ms at {:g} Hz): each frame misses "
                "refreshes (--frame-budget-ms)",
                settings_.frame_budget_ms, refresh_ms, display_refresh_hz_)
          : "";
  r.stage = fmt::format("realtime: fovea {} ({:.0f} %){}{}{}{}{}{}", f.fovea_done ? "converged" : "refining", 100 * f.fovea_converged,
                        f.predicted ? ", at the predicted landing" : "",
                        f.lowered                         ? fmt::format(", a smaller size from the view at hand{}",
                                                f.kept_pixels > 0 ? fmt::format(": {} px kept their rays", f.kept_pixels) : "")
                        : f.new_view && f.kept_pixels > 0 ? fmt::format(", a new view: {} px kept their rays", f.kept_pixels)
                                                          : "",
                        f.scale < 1 || loop_->size_held() ? ", " + loop_->note() : "",
                        f.rebuilding ? fmt::format(", building the view at {}x{}", f.rebuild_width, f.rebuild_height) : "",
                        gaze_note.empty() ? "" : "; " + gaze_note, budget_note);
  r.gaze = f.gaze_px / f.scale;  // (the frame's own size: the loop's scale() may be the next frame's)
  r.stats.ao_rays = f.rays;
  r.stats.ao_ms = f.trace_ms;
  r.stats.total_ms = f.ms;
  const int w = settings_.render.width, h = settings_.render.height;
  if (f.color.width == w && f.color.height == h)
    r.fov = std::move(f.color);
  else  // the loop lowered its resolution: shown scaled up
    r.fov = scaled_nearest(f.color, w, h);
  sh.any = true;
  sh.converged = f.fovea_done;
  base_dirty_ = true;
}

void ViewSession::compose(const Overlays& overlays) {
  const int w = settings_.render.width, h = settings_.render.height;
  const Shown& sh = *shown_state_;
  // Two layers: the regions (heat map, contours, sharp tint) change with the fixation and the
  // image, the marks (gaze, scan path) with every sample; each is redrawn only when it changed
  auto point = [](const std::optional<glm::dvec2>& p) { return p ? fmt::format("{},{}", p->x, p->y) : std::string("-"); };
  Overlays regions = overlays, marks = overlays;
  regions.gaze = regions.scanpath = false;
  marks.contours = marks.budget = marks.sharp = false;
  const std::string region_key = fmt::format("{}|{}", to_string(regions), point(fixation_));
  const std::string mark_key = fmt::format("{}|{}|{}|{}|{}", to_string(marks), point(raw_gaze_), point(fixation_), scanpath_.size(),
                                           scanpath_.empty() ? std::string() : point(scanpath_.back()));
  if (!base_dirty_ && region_key == region_key_ && mark_key == mark_key_) return;
  const bool regions_changed = base_dirty_ || region_key != region_key_;
  region_key_ = region_key;
  mark_key_ = mark_key;
  if (base_dirty_) {
    base_dirty_ = false;
    const int panes = this->panes();
    base_ = Rgba8(w * panes, h);
    std::fill(base_.px.begin(), base_.px.end(), uint8_t(40));
    const Result& r = sh.result;
    auto put = [&](const Image& img, int pane) {
      if (img.width == w && img.height == h) paste(base_, to_rgba8(img), pane * w, 0);
    };
    if (settings_.mode == ViewMode::vision) {
      put(r.perceived, 0);
    } else if (settings_.mode == ViewMode::side_by_side) {
      put(r.fov, 0);
      put(r.ref, 1);
      if (!r.fov.empty() && !r.ref.empty()) put(difference(r.fov, r.ref, settings_.diff_gain), 2);
    } else {
      put(settings_.mode == ViewMode::reference ? r.ref : r.fov, 0);
    }
  }
  OverlayInputs in;
  in.gaze = raw_gaze_;
  in.fixation = fixation_;
  in.scanpath = scanpath_;
  std::optional<FoveationModel> model;
  const glm::dvec2 centre(w * 0.5, h * 0.5);
  if (settings_.mode != ViewMode::vision) {
    model.emplace(settings_.render.display, w, h, fixation_.value_or(centre), settings_.render.foveation);
    in.model = &*model;
  } else if (sh.result.coc.size() == static_cast<size_t>(w) * h) {
    in.coc_px = &sh.result.coc;
    in.sharp_px = settings_.vision.sharp_px;
  }
  if (regions_changed) {
    layered_ = base_;
    for (int pane = 0; pane < panes(); ++pane) draw_overlays(layered_, pane * w, 0, w, h, regions, in);
  }
  shown_ = layered_;
  for (int pane = 0; pane < panes(); ++pane) draw_overlays(shown_, pane * w, 0, w, h, marks, in);
}

ViewStatus ViewSession::status() const {
  const Shown& sh = *shown_state_;
  ViewStatus st;
  st.stage = sh.any ? (sh.result.error.empty() ? sh.result.stage : "error: " + sh.result.error) : "starting";
  st.converged = sh.converged;
  st.progress = worker_->progress.load();
  st.render_ms = sh.result.step ? sh.result.step->total_ms : sh.result.stats.total_ms;
  st.ao_rays = sh.result.stats.ao_rays;
  st.rays_per_s = sh.result.stats.ao_ms > 0 ? sh.result.stats.ao_rays / (sh.result.stats.ao_ms / 1000.0) : 0.0;
  st.gaze = raw_gaze_;
  st.fixation = fixation_;
  st.render_gaze = sh.result.gaze;
  st.source = gaze_.source ? fmt::format("{} ({})", gaze_.source->name(), to_string(gaze_.source->state())) : "fixed";
  st.step = sh.result.step;
  return st;
}

bool ViewSession::wait_until_converged(double timeout_s, const Overlays& overlays) {
  const Timer clock;
  for (;;) {
    update(overlays);
    if (shown_state_->converged) return true;
    if (clock.ms() > timeout_s * 1000) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

nlohmann::json ViewSession::stats_json() const {
  const ViewStatus st = status();
  const FrameStats& f = shown_state_->result.stats;
  nlohmann::json j = {{"settings", settings_json(settings_)},
                      {"camera", camera_json(camera_)},
                      {"scene", {{"source", scene_.source}, {"triangles", tracer_.triangles()}}},
                      {"stage", st.stage},
                      {"converged", st.converged},
                      {"gaze_source", st.source},
                      {"gaze_px", point_json(st.gaze)},
                      {"fixation_px", point_json(st.fixation)},
                      {"render_gaze_px", {st.render_gaze.x, st.render_gaze.y}},
                      {"image_px", {shown_.width, shown_.height}}};
  if (settings_.mode != ViewMode::vision)
    j["frame"] = {
        {"ao_rays", f.ao_rays},
        {"ao_rays_per_pixel", f.ao_rays_mean},
        {"ao_rays_per_second", st.rays_per_s},
        {"time_ms",
         {{"primary", f.primary_ms}, {"foveation", f.foveation_ms}, {"ao", f.ao_ms}, {"shade", f.shade_ms}, {"total", f.total_ms}}}};
  if (st.step)
    j["vision_step"] = {{"step", st.step->step},
                        {"focus_px", {st.step->focus_px.x, st.step->focus_px.y}},
                        {"focus_depth_m", std::isfinite(st.step->focus_depth_m) ? nlohmann::json(st.step->focus_depth_m) : "inf"},
                        {"sharp_fraction", st.step->sharp_fraction},
                        {"blink", st.step->blink},
                        {"time_ms",
                         {{"trace", st.step->trace_ms},
                          {"features", st.step->features_ms},
                          {"sharpness", st.step->sharpness_ms},
                          {"blur", st.step->blur_ms},
                          {"total", st.step->total_ms}}}};
  return j;
}

void ViewSession::save_screenshot(const std::string& png_path, nlohmann::json extra) const {
  save_rgba8(shown_, png_path);
  nlohmann::json j = stats_json();
  j["image"] = png_path;
  for (auto& [k, v] : extra.items()) j[k] = v;
  write_json_file(std::filesystem::path(png_path).replace_extension(".json").string(), j);
}

}  // namespace foveal
