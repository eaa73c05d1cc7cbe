// foveal/render/realtime.cpp — the deadline loop: base shading once per view, AO rays by perceived
// error within each frame's budget, the fovea at a saccade's predicted landing.
#include "foveal/render/realtime.h"

#include "foveal/render/reuse_pixel.h"
#include "foveal/util/error.h"
#include "foveal/util/gaze_point.h"
#include "foveal/util/stats.h"
#include "foveal/util/timer.h"
#include "foveal/util/units.h"

#include <fmt/format.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

namespace foveal {

namespace {

constexpr uint32_t kFirstRound = 16;   // a pixel's first round of rays (adaptive sampling's)
constexpr int kBuckets = 64;           // priority buckets of the periphery (half powers of two)
constexpr int kRings = 64;             // the rays ahead's rings of a degree of eccentricity
constexpr double kSlipDecay = 0.995;   // per frame: the margin's memory of a late end
constexpr double kSlipPad = 0.5;       // ms kept beyond the latest slip
constexpr double kRestMs = 500;        // a camera still this long is at rest: a size lowered for its motion comes back
constexpr double kGrowth = 1.1;        // a moving camera's size grows by this factor at least, or to the size before it moved
constexpr double kGrowthShare = 0.75;  // … to where its frame's work would take this share of the time to the deadline
// A moved view's cost over a fresh one's until one is measured: the rays kept, 1.4–1.6 on the
// dragon at 840×525 while the surfaces were copied into the history (less now that they move)
constexpr double kCarryCost = 1.6;
// A still view lowered again within kFlapFrames (10 s at 60 Hz) of growing back waits that long
// before it grows again, then twice as long each time, up to kMaxHoldFrames (2
// minutes at 60 Hz), unless the budget grows by kHoldBudgetRise (lowered_still)
constexpr int kFlapFrames = 600;
constexpr int kMaxHoldFrames = 7200;
constexpr double kHoldBudgetRise = 1.25;
constexpr int kEstimateEvery = 4;  // frames between estimates of the pixels without rays (estimate_unreached)
// The maps follow the gaze (update_maps) in a box around the fovea, kMapsBoxBeyondDeg of effective
// eccentricity beyond the fovea's reach up and down from the gaze, at least kMapsBoxDeg (times the
// ellipse's ratio across); outside it they are evaluated again once the gaze is kMapsStaleDeg from
// where they last were everywhere
constexpr double kMapsBoxDeg = 6.0;
constexpr double kMapsBoxBeyondDeg = 3.0;
constexpr double kMapsStaleDeg = 0.5;
// A view's first rays include a coarse grid, every kCoarseGrid-th pixel in each direction
// (plan_round): spread over the view, they make the estimate of the pixels still without
// rays an interpolation of measured values rather than the fovea's carried outwards
constexpr size_t kCoarseGrid = 16;
// … kCoarseRound rays each: its noise, spread by the estimate over the pixels around it, showed as
// a mottle of 16-pixel blotches with a first round's 16 (the sphere over the plane's unreached
// pixels 0.022 off on average against 0.020 with 64; at 840×525 some 90,000 rays)
constexpr uint32_t kCoarseRound = 64;

// body(i) for every pixel, in parallel blocks of 4096
template <class Body>
void for_each_pixel(size_t n, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) body(i);
  });
}

// The render size at `scale` of the size asked for
glm::ivec2 scaled_size(const RenderParams& requested, double scale) {
  return {std::max(1, static_cast<int>(std::lround(requested.width * scale))),
          std::max(1, static_cast<int>(std::lround(requested.height * scale)))};
}

// Pixels [b, e)'s unit eye rays in single precision (the maps' input that the gaze leaves alone)
void eye_rays(const FoveationModel& model, size_t width, size_t b, size_t e, float* x, float* y, float* z) {
  for (size_t i = b; i < e; ++i) {
    const glm::vec3 r(glm::normalize(model.eye_ray(static_cast<double>(i % width) + 0.5, static_cast<double>(i / width) + 0.5)));
    x[i] = r.x;
    y[i] = r.y;
    z[i] = r.z;
  }
}

// Entries [b, e) of the maps from the unit eye rays: foveation_maps()'s model in single precision
// (a full-frame loop keeps only E: every pixel at q = 1 with n_max rays)
void evaluate_maps(const FoveationModel& model, const FoveationParams& f, bool foveated, const float* x, const float* y, const float* z,
                   size_t b, size_t e, FoveationMaps& maps) {
  model.evaluate_directions_fast(x + b, y + b, z + b, e - b, maps.eccentricity.data() + b, maps.quality.data() + b, maps.rays.data() + b,
                                 foveated ? maps.blend.data() + b : nullptr);
  if (foveated) return;
  std::fill_n(maps.quality.data() + b, e - b, 1.0f);
  std::fill_n(maps.rays.data() + b, e - b, static_cast<uint16_t>(f.max_rays));
  std::fill_n(maps.blend.data() + b, e - b, f.max_rays > 0 ? 1.0f : 0.0f);
}

// Pixel i sees a surface and asks for rays (n(E) > 0), and has none (`rays`: its rays so far): the
// estimate of the pixels without rays stands in for its own
bool unreached_pixel(const GBuffer& g, const FoveationMaps& maps, size_t i, float rays) {
  return rays == 0 && g.hit(i) && maps.rays[i] > 0;
}

// The estimate of the pixels without rays (RealtimeLoop::estimate_unreached), the pull of rows
// [y0, y1) of the pyramid's first level: a pixel is known where it sees a surface and has rays, its
// value the share of them found open (`cast(i)`, `open(i)`). True where a pixel that sees a surface
// and asks for rays (n(E) > 0) has none
template <class Cast, class Open>
bool pull_unreached(PullPush& p, const GBuffer& g, const FoveationMaps& maps, const Cast& cast, const Open& open, int y0, int y1) {
  std::atomic<bool> unreached{false};
  p.pull_rows(
      g.width, g.height,
      [&](size_t i) {
        const float rays = cast(i);
        if (unreached_pixel(g, maps, i, rays) && !unreached.load(std::memory_order_relaxed))
          unreached.store(true, std::memory_order_relaxed);
        return std::pair{rays > 0 && g.hit(i), rays > 0 ? open(i) / rays : 0.0f};
      },
      y0, y1);
  return unreached;
}

// Every vector of `rows` appended to `g`'s (rows that follow those `g` holds)
void append_rows(GBuffer& g, const GBuffer& rows) {
  auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
  append(g.prim, rows.prim);
  append(g.position, rows.position);
  append(g.normal, rows.normal);
  append(g.geo_normal, rows.geo_normal);
  append(g.albedo, rows.albedo);
  append(g.depth, rows.depth);
  append(g.view, rows.view);
}

}  // namespace

const char* to_string(LoopClock clock) { return clock == LoopClock::model ? "model" : "wall"; }

LoopClock parse_loop_clock(const std::string& name) {
  if (name == "wall") return LoopClock::wall;
  if (name == "model") return LoopClock::model;
  fail("clock: unknown clock '{}' (known: wall, model)", name);
}

double loop_margin_ms(double budget_ms, std::optional<double> margin_ms) {
  return margin_ms.value_or(std::min(kDefaultMarginMs, 0.25 * budget_ms));
}

double loop_margin_ms(const LoopSettings& s) { return loop_margin_ms(s.budget_ms, s.margin_ms); }

namespace {

// `name`: the option or attribute that set it (frame_budget_ms where the loop is made, budget_ms on
// RealtimeLoop::set_budget_ms and Python's Loop.budget_ms)
void check_budget(double budget_ms, const char* name) {
  if (!(budget_ms > 0) || !std::isfinite(budget_ms) || budget_ms > 10000) fail("{}: must be in (0, 10000] ms, got {}", name, budget_ms);
}

}  // namespace

void validate(const LoopSettings& s) {
  check_budget(s.budget_ms, "frame_budget_ms");
  if (s.clock == LoopClock::model) {
    if (!(s.model_rays_per_ms > 0) || !std::isfinite(s.model_rays_per_ms))
      fail("model_rays_per_ms: the model clock needs a ray rate > 0, got {}", s.model_rays_per_ms);
    if (!(s.model_fixed_ms >= 0) || !std::isfinite(s.model_fixed_ms)) fail("model_fixed_ms: must be >= 0, got {}", s.model_fixed_ms);
  }
  if (s.margin_ms && (!(*s.margin_ms >= 0) || *s.margin_ms >= s.budget_ms))
    fail("margin_ms: must be in [0, the frame budget {:g} ms), got {}", s.budget_ms, *s.margin_ms);
  if (!(s.periphery_share > 0 && s.periphery_share <= 1))
    fail("periphery_share: must be in (0, 1] (the share of the frame budget the periphery's rays may run to), got {}", s.periphery_share);
  if (!(s.min_scale > 0 && s.min_scale <= 1)) fail("min_scale: must be in (0, 1], got {}", s.min_scale);
  if (!(s.slowdown >= 1) || !std::isfinite(s.slowdown)) fail("slowdown: must be >= 1, got {}", s.slowdown);
  if (s.estimate_cost_ms && !(*s.estimate_cost_ms >= 0)) fail("estimate_cost_ms: must be >= 0, got {}", *s.estimate_cost_ms);
  if (s.fixed_part_ms && !(*s.fixed_part_ms >= 0)) fail("fixed_part_ms: must be >= 0, got {}", *s.fixed_part_ms);
  if (s.rebuild_rows_per_frame && *s.rebuild_rows_per_frame < 1)
    fail("rebuild_rows_per_frame: must be >= 1, got {}", *s.rebuild_rows_per_frame);
  validate(s.landing);
}

RealtimeLoop::RealtimeLoop(FrameRenderer& renderer, const Scene& scene, const RenderParams& params, const LoopSettings& settings)
    : renderer_(renderer),
      scene_(scene),
      requested_(params),
      params_(params),
      settings_(settings),
      given_margin_ms_(settings.margin_ms),
      predictor_(settings.landing) {
  validate(params);
  validate(settings);
  if (params.shadows) fail("shadows: the real-time loop shades without shadow rays (as the papers' frames)");
  const Bounds bounds = scene.bounds();
  ao_distance_ = resolve_ao_distance(scene, bounds, params.ao_distance);
  epsilon_ = surface_epsilon(bounds);
  // τ where q = 1: the reference's worst-case noise at n_max rays, times the tolerance
  tau_fovea_ = static_cast<float>(params.reuse.tolerance * 0.5 / std::sqrt(std::max(1, params.foveation.max_rays)));
  sweep_.set_budget(settings.budget_ms);
  narrow_sweep_.set_budget(settings.budget_ms);
  estimate_cost_.set_budget(settings.budget_ms);
}

glm::dvec2 RealtimeLoop::px_to_deg(glm::dvec2 px) const {
  const Display& d = requested_.display;
  return {std::atan((px.x / requested_.width - 0.5) * d.width_cm / d.distance_cm) * kDeg,
          std::atan((px.y / requested_.height - 0.5) * d.height_cm / d.distance_cm) * kDeg};
}

glm::dvec2 RealtimeLoop::deg_to_px(glm::dvec2 deg) const {
  const Display& d = requested_.display;
  return {(std::tan(deg.x / kDeg) * d.distance_cm / d.width_cm + 0.5) * requested_.width,
          (std::tan(deg.y / kDeg) * d.distance_cm / d.height_cm + 0.5) * requested_.height};
}

void RealtimeLoop::push_gaze(double t_s, std::optional<glm::dvec2> gaze_px) {
  if (!std::isfinite(t_s)) fail("t_s: must be a finite time in seconds, got {}", t_s);
  if (gaze_px && (std::isinf(gaze_px->x) || std::isinf(gaze_px->y)))  // (an infinity is no lost sample: a unit or scale gone wrong)
    fail("gaze_px: ({}, {}) is no point; NaN marks a lost sample", gaze_px->x, gaze_px->y);
  if (gaze_px && std::isfinite(gaze_px->x) && std::isfinite(gaze_px->y))  // NaN: a lost sample; a finite point must be near the image
    check_gaze_point("gaze_px", gaze_px->x, gaze_px->y, requested_.width, requested_.height);
  if (last_pushed_s_ && t_s <= *last_pushed_s_) {
    if (*last_pushed_s_ - t_s <= kClockRestartS) return;  // repeated, or out of order: older than what is shown
    ++clock_restarts_;                                    // the clock restarted: its samples are taken from here on
    clock_back_s_ = *last_pushed_s_ - t_s;
    predictor_.push(t_s, glm::dvec2(NAN), false);  // a flight across the restart is no saccade
    last_sample_s_.reset();
  }
  last_pushed_s_ = t_s;
  const bool valid = gaze_px && std::isfinite(gaze_px->x) && std::isfinite(gaze_px->y);
  if (valid) {
    measured_px_ = *gaze_px;
    if (last_sample_s_ && t_s > *last_sample_s_) intervals_s_.add(t_s - *last_sample_s_);
    last_sample_s_ = t_s;
  }
  predictor_.push(t_s, valid ? px_to_deg(*gaze_px) : glm::dvec2(NAN), valid);
}

std::string RealtimeLoop::gaze_note() const {
  std::string note;
  if (settings_.predict && intervals_s_.size() >= 16) {
    const double median = intervals_s_.median();
    const std::string unseen = unseen_saccades_note(median, "the loop");
    note = unseen.empty() ? late_landing_note(gaze_sample_hz())
                          : fmt::format("gaze samples come {:.3g} s apart (the median of the latest 16): {}", median, unseen);
  }
  if (clock_restarts_ > 0)
    note += fmt::format(
        "{}the gaze samples' clock went back {}, the latest time by {:.3g} s: each time the loop took the samples from there "
        "on{}; give every sample one increasing clock (a trial clock that restarts is not one)",
        note.empty() ? "" : "; ", clock_restarts_ == 1 ? std::string("once") : fmt::format("{} times", clock_restarts_), clock_back_s_,
        settings_.predict ? " and the landing predictor started afresh" : "");
  return note;
}

void RealtimeLoop::set_budget_ms(double budget_ms) {
  check_budget(budget_ms, "budget_ms");
  LoopSettings s = settings_;
  s.budget_ms = budget_ms;
  // (from the margin given, so that a budget lowered for one frame does not shrink it for good; a
  // margin asked for is kept up to half the budget, the default one within a quarter)
  if (given_margin_ms_) s.margin_ms = std::min(*given_margin_ms_, 0.5 * budget_ms);
  validate(s);
  settings_ = s;
  sweep_.set_budget(budget_ms);
  narrow_sweep_.set_budget(budget_ms);
  estimate_cost_.set_budget(budget_ms);
}

void RealtimeLoop::reset() {
  rebuild_.reset();
  have_view_ = false;
  forget_ = true;
  maps_gaze_.reset();
}

void RealtimeLoop::pixel_counts(size_t i, glm::vec3 position, float& open, float& cast, glm::vec3& origin_sum) const {
  const bool earlier = any_kept();
  const float own = static_cast<float>(cast_[i]);
  open = static_cast<float>(open_[i]) + (earlier ? kept_open_[i] : 0.0f);
  cast = own + (earlier ? kept_cast_[i] : 0.0f);
  origin_sum = own * position + (earlier ? kept_origin(i, position) : glm::vec3(0.0f));
}

void RealtimeLoop::keep_rays() {
  // The view is replaced next: its surfaces move into the history, its counts are read where they are
  history_.store(std::move(gbuffer_), camera_, maps_, params_.reuse,
                 [&](size_t i, glm::vec3 position, float& open, float& cast, glm::vec3& origin_sum) {
                   pixel_counts(i, position, open, cast, origin_sum);
                 });
}

void RealtimeLoop::shade(const GBuffer& g, const Camera& camera, size_t b, size_t e, std::vector<glm::vec3>& lit,
                         std::vector<glm::vec3>& ambient) const {
  // S and A of the colour S + k_a·A: eq. 2 with k_a = 0, and the ambient light times the albedo
  const std::vector<Light> lights = frame_lights(scene_.lights, camera);
  const std::vector<MaterialView> materials = material_views(scene_);
  for_each_pixel(e - b, [&](size_t k) {
    const size_t i = b + k;
    if (!g.hit(i)) {
      lit[i] = background_colour();
      ambient[i] = glm::vec3(0.0f);
      return;
    }
    const MaterialView& m = materials[scene_.material_ids[g.prim[i]]];
    lit[i] = shade_point(m, g.albedo[i], g.position[i], g.normal[i], g.geo_normal[i], g.view[i], 0.0f, scene_.ambient, lights.data(),
                         static_cast<int>(lights.size()), false, epsilon_, [](const Ray&) { return false; });
    ambient[i] = scene_.ambient * g.albedo[i];
  });
}

bool RealtimeLoop::new_view(const Camera& camera, uint64_t& kept_pixels) {
  // The rays so far, for the new view to take over where it sees the same surfaces (not after
  // reset(), nor where there was no view yet)
  const size_t before = gbuffer_.prim.size();
  const bool carry = settings_.keep_history && !forget_ && before > 0 && cast_.size() == before && maps_.quality.size() == before;
  if (carry)
    keep_rays();
  else
    history_.clear();
  forget_ = false;
  gbuffer_ = renderer_.surfaces(camera, params_.width, params_.height);
  ++gbuffer_version_;
  traced_size_ = glm::ivec2(params_.width, params_.height);
  traced_pixels_.reset();
  // What the view's first rays would otherwise pay in the frame after it: the device's copy of the
  // surfaces, and room for a task per pixel
  renderer_.prepare_ao_batches(gbuffer_, gbuffer_version_);
  camera_ = camera;
  have_view_ = true;
  const size_t n = gbuffer_.prim.size();
  lit_.resize(n);
  ambient_.resize(n);
  shade(gbuffer_, camera, 0, n, lit_, ambient_);
  cast_.assign(n, 0);
  open_.assign(n, 0);
  estimates_ = false;  // (those of the view before)
  // The coarse grid (plan_round), except where views follow one another without keeping rays (a
  // camera moving with keep_history off): there the next view would lose its rays unshown
  grid_pending_ = carry || !last_new_view_;
  prepare_rounds(n);
  // The maps at the latest gaze (the frame moves them where a prediction says), then what the
  // view keeps of the rays before: the renderer's temporal reprojection (reuse.h)
  maps_gaze_.reset();
  update_maps(measured_px_.value_or(glm::dvec2(requested_.width * 0.5, requested_.height * 0.5)) * scale_, false);
  kept_pixels = carry ? history_.reproject(gbuffer_, maps_, params_.reuse, counts_) : 0;
  if (kept_pixels > 0) {
    kept_open_.swap(counts_.open);
    kept_cast_.swap(counts_.cast);
    kept_origin_.swap(counts_.origin_sum);
  } else {  // nothing kept: no pixel reads them (any_kept())
    kept_open_.clear();
    kept_cast_.clear();
    kept_origin_.clear();
  }
  // A fresh view casts each pixel's sequence from its start, the paper's rays; one that carries rays
  // on casts a sequence scrambled for the view (a later stretch of one sequence is less evenly
  // spread than any sequence's start: the renderer's temporal rule, reuse_pixel.h)
  ++views_;
  view_seed_ = any_kept() ? scrambled_seed(params_.seed, views_) : params_.seed;
  // What composing this view takes, before the first frame's deadline relies on it
  Image scratch;
  const Timer compose_timer;
  compose(scratch);
  finish_ms_ = compose_timer.ms();
  // Two images in hand for the view's first frames, their memory touched here: the first frame is
  // composed into one, the second into the other while the first is shown (a caller hands an image
  // back once the next is on screen). The second frame of every loop used to compose into a fresh
  // 5 MB image at 840×525: 1,245 page faults, composing 2.5 ms over its plan, and late in 2 of 6
  // runs of bench latency (IRF S1 and the EyeLink recording, 10 s each, the 2-core AMD EPYC VM)
  recycle(std::move(scratch));
  if (std::count_if(spares_.begin(), spares_.end(), [&](const Image& i) { return fits_view(i); }) < 2)
    recycle(Image(params_.width, params_.height, 3));
  return carry;
}

void RealtimeLoop::update_maps(glm::dvec2 gaze_px, bool predicted) {
  // The maps follow the gaze once it has moved a tenth of a degree (a fixation's tremor and the
  // tracker's noise move it less; recomputing the model at every pixel costs milliseconds)
  const double ppd = pixels_per_degree(params_.display) * params_.width / params_.display.res_x;
  const double threshold_px = std::max(0.5, 0.1 * ppd);
  const bool same_size = maps_.width == params_.width && maps_.height == params_.height;
  if (maps_gaze_ && glm::length(*maps_gaze_ - gaze_px) < threshold_px && same_size && predicted == maps_predicted_) return;
  all_converged_ = false;
  // foveation_maps()'s model in single precision, from the pixels' unit eye rays kept per size
  const size_t n = static_cast<size_t>(params_.width) * static_cast<size_t>(params_.height);
  const FoveationModel model(params_.display, params_.width, params_.height, gaze_px, params_.foveation);
  if (ray_x_.size() != n) {  // the unit eye rays, as three arrays (the maps' loop vectorises over each)
    ray_x_.resize(n);
    ray_y_.resize(n);
    ray_z_.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      eye_rays(model, static_cast<size_t>(params_.width), r.begin(), r.end(), ray_x_.data(), ray_y_.data(), ray_z_.data());
    });
  }
  maps_.width = params_.width;
  maps_.height = params_.height;
  maps_.quality.resize(n);
  maps_.eccentricity.resize(n);
  maps_.rays.resize(n);
  maps_.blend.resize(n);
  const bool foveated = params_.mode == RenderMode::foveated;
  // Within a fixation (the gaze within kMapsStaleDeg of where the maps were last evaluated
  // everywhere) only a box around the fovea, where q(E) is steep;
  // outside it the maps keep a gaze at most a degree from this one (two gazes each within
  // kMapsStaleDeg of the same one), less than a tracker's accuracy moves it. At the papers' display
  // the fovea reaches 3.8° (q = 1), the box 6.8° (q ≈ 0.6, n(E) changing by 28 rays a degree of 400,
  // less further out) and holds a quarter of the pixels. The model at every pixel took 1.2–2.6 ms
  // of a 16.7-ms frame at 840×525 on two cores, and a tracker's noise moved the gaze a tenth of a
  // degree in most frames of a fixation.
  const int w = params_.width, h = params_.height;
  const double reach = model.fovea_reach_deg(), box_deg = std::max(kMapsBoxDeg, reach + kMapsBoxBeyondDeg);
  const int half_y = static_cast<int>(std::ceil(box_deg * ppd));
  const int half_x = static_cast<int>(std::ceil(box_deg * params_.foveation.ellipse_ratio * ppd));
  const glm::ivec4 box(std::max(0, static_cast<int>(gaze_px.x) - half_x), std::max(0, static_cast<int>(gaze_px.y) - half_y),
                       std::min(w, static_cast<int>(gaze_px.x) + half_x + 1), std::min(h, static_cast<int>(gaze_px.y) + half_y + 1));
  const bool in_box = foveated && maps_gaze_ && maps_full_gaze_ && same_size &&
                      glm::length(*maps_full_gaze_ - gaze_px) <= kMapsStaleDeg * ppd && box.x < box.z && box.y < box.w;
  // (The box's pixels span fewer degrees away from the screen's centre, more so on a wide display:
  // where its edge comes within the fovea's reach and the maps' staleness, plus half a degree,
  // every pixel is evaluated after all; eccentricity grows outwards from the gaze, so its edge holds
  // the least of all the pixels outside it)
  bool boxed = false;
  if (in_box) {
    tbb::parallel_for(tbb::blocked_range<int>(box.y, box.w, 8), [&](const tbb::blocked_range<int>& r) {
      for (int y = r.begin(); y != r.end(); ++y) {
        const size_t row = static_cast<size_t>(y) * static_cast<size_t>(w);
        evaluate_maps(model, params_.foveation, foveated, ray_x_.data(), ray_y_.data(), ray_z_.data(), row + static_cast<size_t>(box.x),
                      row + static_cast<size_t>(box.z), maps_);
      }
    });
    const auto e = [&](int x, int y) {
      return maps_.eccentricity[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)];
    };
    float edge = std::numeric_limits<float>::infinity();
    for (int x = box.x; x < box.z; ++x) {
      if (box.y > 0) edge = std::min(edge, e(x, box.y));
      if (box.w < h) edge = std::min(edge, e(x, box.w - 1));
    }
    for (int y = box.y; y < box.w; ++y) {
      if (box.x > 0) edge = std::min(edge, e(box.x, y));
      if (box.z < w) edge = std::min(edge, e(box.z - 1, y));
    }
    boxed = edge >= reach + 2 * kMapsStaleDeg + 0.5;
  }
  if (boxed) {
    maps_box_ = box;
    // A pixel may now lack the rays its n(E) asks for only in the box: where none lacked any before,
    // the estimate of the pixels without rays (a pass over every pixel) is made only where a pixel
    // of the box now does. (Each drift of a fixation made one, at a converged view for nothing.)
    if (!unreached_possible_) {
      std::atomic<bool> lacking{false};
      tbb::parallel_for(tbb::blocked_range<int>(box.y, box.w, 8), [&](const tbb::blocked_range<int>& r) {
        for (int y = r.begin(); y != r.end() && !lacking.load(std::memory_order_relaxed); ++y) {
          const size_t row = static_cast<size_t>(y) * static_cast<size_t>(w);
          for (size_t i = row + static_cast<size_t>(box.x), e = row + static_cast<size_t>(box.z); i < e; ++i)
            if (unreached_pixel(gbuffer_, maps_, i, total_cast(i))) {
              lacking.store(true, std::memory_order_relaxed);
              break;
            }
        }
      });
      unreached_possible_ = lacking;
    }
    periphery_keys_.stale_box(box, static_cast<size_t>(w));
    ahead_keys_.stale_box(box, static_cast<size_t>(w));
  } else {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      evaluate_maps(model, params_.foveation, foveated, ray_x_.data(), ray_y_.data(), ray_z_.data(), r.begin(), r.end(), maps_);
    });
    maps_full_gaze_ = gaze_px;
    maps_box_ = glm::ivec4(0, 0, w, h);
    ++maps_everywhere_;
    reached_ = true;             // (n(E) changed everywhere: a pixel may now lack rays it did not need)
    unreached_possible_ = true;  // (estimate_unreached looks for pixels without rays)
    periphery_keys_.stale_all();
    ahead_keys_.stale_all();
  }
  maps_gaze_ = gaze_px;
  collect_fovea(gaze_px, predicted);
}

void RealtimeLoop::collect_fovea(glm::dvec2 gaze_px, bool predicted) {
  // The fovea's pixels, in pixel order (centre-out measured slower to converge the whole fovea on
  // IRF S1, 151–170 ms against 101–117 ms: the rim waited while the centre followed the drift)
  // (q = 1 lies inside the box the maps were evaluated in, which reaches kMapsBoxBeyondDeg
  // beyond it; outside it the maps' gaze is at most a degree off: update_maps)
  const auto w = static_cast<size_t>(maps_.width);
  fovea_.clear();
  for (auto y = static_cast<size_t>(maps_box_.y); y < static_cast<size_t>(maps_box_.w); ++y)
    for (size_t i = y * w + static_cast<size_t>(maps_box_.x), e = y * w + static_cast<size_t>(maps_box_.z); i < e; ++i)
      if (maps_.quality[i] >= 1.0f && gbuffer_.hit(i) && maps_.rays[i] > 0) fovea_.push_back(static_cast<uint32_t>(i));
  // A predicted landing's fovea centre-out instead: a frame's rays rarely cover a fresh fovea, and
  // pixel order spent them on its top rows, the part a prediction off by a degree or two most
  // often misses (measured: a 10.3° saccade predicted 22 px too high got none of its landed
  // fovea's middle rows in three frames, and converged two frames after the loop without
  // prediction). The centre is where the landing most likely is.
  maps_predicted_ = predicted;
  if (predicted) {
    auto ring = [&](uint32_t i) {
      const double dx = static_cast<double>(i % w) + 0.5 - gaze_px.x, dy = static_cast<double>(i / w) + 0.5 - gaze_px.y;
      return static_cast<size_t>(std::sqrt(dx * dx + dy * dy));
    };
    size_t rings = 0;
    for (const uint32_t i : fovea_) rings = std::max(rings, ring(i) + 1);
    std::vector<uint32_t> count(rings + 1, 0);  // a counting sort by whole pixels of distance: stable, O(n)
    for (const uint32_t i : fovea_) ++count[ring(i) + 1];
    for (size_t r = 1; r < count.size(); ++r) count[r] += count[r - 1];
    fovea_scratch_.resize(fovea_.size());  // (not the sweep's order_: swapped, it lost the room of every pixel)
    for (const uint32_t i : fovea_) fovea_scratch_[count[ring(i)]++] = i;
    fovea_.swap(fovea_scratch_);
  }
}

bool RealtimeLoop::converged(size_t i) const {
  const uint32_t n = maps_.rays[i];
  if (!gbuffer_.hit(i) || n == 0) return true;
  const float c = total_cast(i);
  if (c >= static_cast<float>(n)) return true;
  // The fovea takes its n_max rays: stopped early at τ it measured 1.02× the reference's noise on
  // the dragon (bench latency; two standard errors above it over 20,000 pixels)
  const float q = maps_.quality[i];
  return q < 1.0f && c >= static_cast<float>(kFirstRound) && q > 0 && visibility_standard_error(total_open(i), c) <= tau_fovea_ / q;
}

void RealtimeLoop::prepare_rounds(size_t n) {
  // A task per pixel at most, and a sweep's order and keys over every pixel, written here where they
  // must grow so that their pages are touched: growing them in the view's first frames cost each of
  // those frames up to 540 page faults at 840×525 (bench latency: a late frame's planning), and
  // reserving alone maps no page. A view no larger than one before (a moving camera's) costs nothing
  if (tasks_.capacity() < n) {
    tasks_.resize(n);
    tasks_.clear();
  }
  const auto grow = [n](auto& v) {
    if (v.capacity() < n) v.assign(n, {});
  };
  grow(blocked_);
  grow(done_);
  grow(order_);
  periphery_keys_.reset(n);
  ahead_keys_.reset(n);
  pull_push_.prepare(params_.width, params_.height);  // (estimate_unreached's pyramid)
}

uint32_t RealtimeLoop::round_rays(size_t i, uint32_t target) const {
  if (!any_kept()) return std::min<uint32_t>(target - cast_[i], std::max(kFirstRound, cast_[i]));
  const float c = total_cast(i);
  const auto lack = static_cast<uint32_t>(std::max(1.0f, std::ceil(static_cast<float>(target) - c)));
  return std::min<uint32_t>({lack, target - cast_[i], std::max(kFirstRound, static_cast<uint32_t>(std::ceil(c)))});
}

int RealtimeLoop::periphery_key(size_t i) const {
  if (converged(i)) return SweepKeys::kNone;
  // A pixel on the coarse grid still without rays goes first: its rays stand for its unreached
  // neighbours too (their estimate), so the periphery's first rays span the view
  const float c = total_cast(i);
  const auto width = static_cast<size_t>(params_.width);
  if (c == 0 && i % width % kCoarseGrid == 0 && i / width % kCoarseGrid == 0) return 0;
  const float q = maps_.quality[i], k = static_cast<float>(round_rays(i, maps_.rays[i]));
  const float p = (total_open(i) + 0.5f) / (c + 1.0f);
  const float gain = q * q * p * (1 - p) * k / (c + k);
  return gain > 0 ? std::clamp(static_cast<int>(-2.0f * std::log2(gain)), 0, kBuckets - 1) : kBuckets;
}

int RealtimeLoop::ahead_key(size_t i) const {
  if (!gbuffer_.hit(i) || total_cast(i) >= static_cast<float>(params_.foveation.max_rays)) return SweepKeys::kNone;
  return std::clamp(static_cast<int>(maps_.eccentricity[i]), 0, kRings - 1);
}

size_t RealtimeLoop::sweep_keys_out_of_date() const {
  size_t wrong = 0;
  for (const auto& [keys, key] :
       {std::pair{&periphery_keys_, &RealtimeLoop::periphery_key}, std::pair{&ahead_keys_, &RealtimeLoop::ahead_key}}) {
    if (keys->size() != cast_.size()) continue;  // (no sweep at this size yet: all stale)
    for (size_t i = 0; i < keys->size(); ++i)
      if (const int8_t k = keys->keys()[i]; k != SweepKeys::kStale && k != (this->*key)(i)) ++wrong;
  }
  return wrong;
}

size_t RealtimeLoop::plan_round(uint64_t ray_limit, uint64_t periphery_limit, uint64_t ahead_limit, Round& round) {
  tasks_.clear();
  round = Round::fovea;
  // What n(E) still lacks, in rounds that double the pixel's rays (kept ones included)
  auto rays_for = [&](size_t i) { return round_rays(i, maps_.rays[i]); };
  uint64_t rays = 0;
  auto add = [&](uint32_t i) {
    const uint32_t r = static_cast<uint32_t>(std::min<uint64_t>(rays_for(i), ray_limit - rays));
    tasks_.push_back({i, cast_[i], r});
    rays += r;
  };
  const auto width = static_cast<size_t>(params_.width), height = static_cast<size_t>(params_.height);
  // A new view's coarse grid first, outside the fovea: every kCoarseGrid-th pixel, kCoarseRound
  // rays each (at 840×525 some 1,400 pixels that see a surface, 90,000 rays: under a third of a
  // frame's on two cores). Until the fovea has converged and the periphery's sweep reaches them,
  // the pixels without rays show the estimate made from these (estimate_unreached): the view's AO
  // measured across it, instead of the fovea's visibility carried outwards. (Only a new view:
  // after a gaze jump the grid has its rays, and the fovea's rounds are its own.)
  if (grid_pending_ && periphery_limit > 0) {
    grid_pending_ = false;
    const uint64_t limit = std::min(ray_limit, periphery_limit);
    for (size_t y = 0; y < height; y += kCoarseGrid)
      for (size_t x = 0; x < width; x += kCoarseGrid) {
        const auto i = static_cast<uint32_t>(y * width + x);
        if (total_cast(i) > 0 || maps_.quality[i] >= 1.0f || converged(i)) continue;
        if (rays >= limit) {
          grid_pending_ = true;
          continue;
        }
        const uint32_t r = static_cast<uint32_t>(std::min<uint64_t>({maps_.rays[i], kCoarseRound, ray_limit - rays}));
        tasks_.push_back({i, cast_[i], r});
        rays += r;
      }
  }
  // While the fovea has unconverged pixels a round is theirs alone (a new view's grid aside): no
  // peripheral pixel gets a ray before the fovea is at full quality
  for (const uint32_t i : fovea_) {
    if (rays >= ray_limit) break;
    if (!converged(i)) add(i);
  }
  if (!tasks_.empty() || periphery_limit == 0) return tasks_.size();
  if (all_converged_) {
    if (ahead_limit == 0 || ahead_done_) return 0;
    round = Round::ahead;
    return plan_ahead(std::min(ray_limit, ahead_limit));
  }
  round = Round::periphery;
  ray_limit = std::min(ray_limit, periphery_limit);
  // Then the periphery by q²·σ̂²·k/(c + k), in buckets of half powers of two from the highest (a
  // pixel's bucket is computed again only where its rays or its maps changed: sweep_keys.h)
  const size_t active = periphery_keys_.sweep<kBuckets + 1>([&](size_t i) { return periphery_key(i); }, order_);
  for (size_t k = 0; k < active && rays < ray_limit; ++k) add(order_[k]);
  all_converged_ = active == 0;
  ahead_done_ = false;  // (whatever the rays ahead had reached before, the maps or the view have changed since)
  return tasks_.size();
}

size_t RealtimeLoop::plan_ahead(uint64_t ray_limit) {
  // Every pixel that sees a surface towards n_max, in rounds that double its rays, by eccentricity
  // from the gaze in whole degrees (nearest first: most saccades are short)
  tasks_.clear();
  const auto n_max = static_cast<uint32_t>(params_.foveation.max_rays);
  const size_t active = ahead_keys_.sweep<kRings>([&](size_t i) { return ahead_key(i); }, order_);
  uint64_t rays = 0;
  for (size_t k = 0; k < active && rays < ray_limit; ++k) {
    const uint32_t i = order_[k];
    const auto r = static_cast<uint32_t>(std::min<uint64_t>(round_rays(i, n_max), ray_limit - rays));
    tasks_.push_back({i, cast_[i], r});
    rays += r;
  }
  ahead_done_ = active == 0;
  return tasks_.size();
}

bool RealtimeLoop::fits_view(const Image& image) const {
  return image.width == params_.width && image.height == params_.height && image.channels == 3;
}

void RealtimeLoop::recycle(Image&& image) {
  if (!fits_view(image)) return;
  for (Image& spare : spares_)
    if (!fits_view(spare)) {
      spare = std::move(image);
      return;
    }
}

void RealtimeLoop::compose(Image& color) {
  // Into a handed-back image where there is one: a fresh 5 MB image costs its page faults, which
  // measured 1–5 ms on a shared VM (the frames that came late), against ~1 ms reused
  color = Image();
  for (Image& spare : spares_)
    if (fits_view(spare)) {
      color = std::move(spare);
      spare = Image();
      break;
    }
  if (color.empty()) color = Image(params_.width, params_.height, 3);
  // The constant ambient term, for pixels without AO (n(E) = 0, or no ray yet): as given, or, unset,
  // the renderer's auto constant — the mean visibility of the fovea's pixels (here of those with
  // rays so far; a finished fovea gives the paper's value). A pixel without a ray used to show
  // visibility 1, no occlusion at all, where the paper's frame shows the constant term
  float k_const = 1.0f;
  if (params_.ambient_constant) {
    k_const = *params_.ambient_constant;
  } else {
    double sum = 0;  // in the fovea's order: pixel order once it is measured, as the renderer sums
    size_t count = 0;
    for (const uint32_t i : fovea_)
      if (const float c = total_cast(i); c > 0) {
        sum += total_open(i) / c;
        ++count;
      }
    if (count > 0) k_const = static_cast<float>(sum / static_cast<double>(count));
  }
  // A pixel that will get rays but has none yet (a fresh view's periphery while it fills in, a
  // fresh fovea) shows its visibility as the pixels around it that have rays have it
  // (estimate_unreached). With the constant term instead, a visible edge swept out through the
  // periphery as it filled in: the default k_const = 1 lit the unreached walls of the dragon box
  // as unoccluded, brighter than the refined ones beside them. (A pixel of n(E) = 0 keeps the
  // constant term, as in the paper's frame.)
  const size_t n = cast_.size();
  for_each_pixel(n, [&](size_t i) {
    const float rays = total_cast(i);
    const float v = rays > 0 ? total_open(i) / rays : estimates_ && maps_.rays[i] > 0 ? pull_push_.estimate(i) : k_const;
    const float b = maps_.blend[i];
    const float ka = b * v + (1 - b) * k_const;
    const glm::vec3 c = lit_[i] + ka * ambient_[i];
    for (int k = 0; k < 3; ++k) color.pixels[i * 3 + static_cast<size_t>(k)] = c[k];
  });
}

bool RealtimeLoop::estimate_unreached(double left_ms) {
  // The pixels without rays take their visibility from those around them that have rays (pull-push,
  // pull_push.h), estimated from the rays so far before a frame casts its own: while pixels lack
  // their rays (after a new view, or new maps), every kEstimateEvery frames, and at once where
  // there was no estimate yet. A pass over every pixel and the pyramid: 1.0–2.5 ms at 840×525 on two
  // cores, so not every frame; between, a pixel reached meanwhile shows its own rays. And only once a
  // pixel outside the fovea has got its first rays since the last (or the maps changed everywhere):
  // while the rays go to the fovea alone the estimate would hardly change, and a fovea that follows
  // a fixation's drift reaches a rim of new pixels every few frames, which made it run every fourth
  // frame of the fixation. (bench/latency_segments.py under the model clock gave every landing of
  // IRF S1 and S2 the same time with this rule as without it.)
  if (!unreached_possible_ || (estimates_ && (++estimate_age_ < kEstimateEvery || !reached_))) return false;
  // Due. Where the frame has no room for it before its rays' deadline (wall clock), it waits for a
  // frame that has: meanwhile its pixels show the estimate before, or their own rays. A frame that
  // evaluated the maps at every pixel (every half degree of gaze) and made the estimate too spent
  // 2.6 ms on both at 840×525 on two cores, and with a budget of 4 ms (what an experiment's own
  // drawing may leave the loop) ended late, every such frame (BENCHMARKS.md). (Made at most four
  // frames late, it still came in the fourth frame of a saccade, whose frames each evaluate the maps
  // everywhere.) A view's first estimate is made at once: there is none to show before it.
  // (Its cost falls a little with each frame that waits, so that one estimate a pause lengthened
  // does not stop them for good: SweepCost.)
  if (estimates_ && settings_.estimate_cost_ms.value_or(estimate_cost_.estimate_ms()) > left_ms) {
    estimate_cost_.skipped();
    return true;
  }
  const Timer estimate_timer;
  reached_ = false;
  pull_push_.prepare(params_.width, params_.height);
  const bool unreached = pull_unreached(
      pull_push_, gbuffer_, maps_, [&](size_t i) { return total_cast(i); }, [&](size_t i) { return total_open(i); }, 0,
      PullPush::first_rows(params_.height));
  pull_push_.pull_levels();
  unreached_possible_ = unreached;
  estimates_ = unreached && pull_push_.push();
  estimate_age_ = 0;
  ++estimates_made_;
  estimate_cost_.swept(estimate_timer.ms());
  return false;
}

bool FixedPartWindow::add(double fixed_ms, double budget_ms, size_t min_frames) {
  latest_.add(fixed_ms);
  return latest_.size() >= std::max<size_t>(1, min_frames) && median_ms() > 0.6 * budget_ms;
}

void SweepCost::swept(double ms) {
  // (the first sweep's own time, not a mean with the untimed guess)
  estimate_ms_ = timed_ ? std::max(0.7 * estimate_ms_ + 0.3 * ms, ms) : ms;
  timed_ = true;
  latest_.add(ms);
}

bool RealtimeLoop::rescale(double fixed_ms, bool in_place) {
  const double target = scale_ * std::sqrt(0.5 * settings_.budget_ms / fixed_ms);
  const double scale = std::clamp(target, settings_.min_scale, 1.0);
  if (scale > 0.95 * scale_) {
    // A size the settings do not allow lower (min_scale): the frames come late, and the note says why
    if (target <= 0.95 * scale_ && !held_note_) {
      held_note_ = fmt::format(
          "the base shading took {:.3g} ms of the {:.3g} ms frame budget at {}x{}, and the size may not go below {:.0f} % of {}x{} "
          "(min_scale): frames come late",
          fixed_ms, settings_.budget_ms, params_.width, params_.height, 100 * settings_.min_scale, requested_.width, requested_.height);
    }
    return false;
  }
  const glm::ivec2 size = scaled_size(requested_, scale);
  std::string note =
      fmt::format("the base shading took {:.3g} ms of the {:.3g} ms frame budget at {}x{}: rendering at {}x{} ({:.0f} %) instead", fixed_ms,
                  settings_.budget_ms, requested_.width, requested_.height, size.x, size.y, 100 * scale);
  // A still view whose frames at this size still end in time (their fixed part within the budget:
  // their rays stop at the deadline) takes its smaller size a few rows a frame: at once, in one
  // frame, taking it cost 4–7.5 ms at 840×525 on two cores, and with its maps and first estimate
  // made that frame take 8–12 ms at a budget of 4 ms. One whose frames are late anyway takes it at
  // once (lower_in_place). (Within the margin of the budget, where the frames had 3.0–3.4 ms of
  // fixed part at 4 ms and ended in time, taking it at once made the next frame late by 4–8 ms.)
  if (in_place && settings_.clock == LoopClock::wall && fixed_ms < settings_.budget_ms) {
    if (rebuild_ && rebuild_->lowering && scale >= 0.95 * rebuild_->scale) return false;  // (under way)
    start_rebuild(scale, std::move(note), true);
    return true;
  }
  if (in_place)
    lower_to_ = scale;
  else
    set_scale(scale);
  note_ = std::move(note);
  return true;
}

std::string RealtimeLoop::size_note(const char* why) const {
  return scale_ < 1 ? fmt::format("rendering at {}x{} ({:.0f} %), {}", params_.width, params_.height, 100 * scale_, why) : "";
}

void RealtimeLoop::take_size(double scale, glm::ivec2 size) {
  held_note_.reset();  // (a size of its own: whether it is held is judged anew)
  scale_ = scale;
  params_.width = size.x;
  params_.height = size.y;
}

void RealtimeLoop::set_scale(double scale) {
  rebuild_.reset();
  lower_to_.reset();
  const double pixels_before = static_cast<double>(params_.width) * params_.height;
  take_size(scale, scaled_size(requested_, scale));
  const double ratio = static_cast<double>(params_.width) * params_.height / pixels_before;  // (as adopt_rebuild)
  plan_ms_ *= ratio;
  sweep_.scale(ratio);
  narrow_sweep_.scale(ratio);
  estimate_cost_.scale(ratio);
  have_view_ = false;
  maps_gaze_.reset();
  ray_x_.clear();
  ray_y_.clear();
  ray_z_.clear();
}

RealtimeLoop::Footprints::Footprints(size_t big_w, size_t big_h, size_t w, size_t h) : big_width(big_w) {
  auto axis = [](size_t big, size_t small) {
    Axis a{std::vector<uint32_t>(small + 1, static_cast<uint32_t>(big)), std::vector<uint32_t>(small)};
    for (size_t b = big; b-- > 0;)
      a.first[std::min(small - 1, static_cast<size_t>((static_cast<double>(b) + 0.5) * static_cast<double>(small) /
                                                      static_cast<double>(big)))] = static_cast<uint32_t>(b);
    for (size_t k = 0; k < small; ++k)
      a.nearest[k] = static_cast<uint32_t>(
          std::min(big - 1, static_cast<size_t>((static_cast<double>(k) + 0.5) * static_cast<double>(big) / static_cast<double>(small))));
    return a;
  };
  columns = axis(big_w, w);
  rows = axis(big_h, h);
}

template <class Rays>
uint32_t RealtimeLoop::Footprints::source(size_t x, size_t y, const Rays& rays) const {
  size_t best = rows.nearest[y] * big_width + columns.nearest[x];
  float most = rays.total_cast(best);
  for (size_t by = rows.first[y]; by < rows.first[y + 1]; ++by)
    for (size_t bx = columns.first[x]; bx < columns.first[x + 1]; ++bx)
      if (const size_t b = by * big_width + bx; rays.total_cast(b) > most) {
        most = rays.total_cast(b);
        best = b;
      }
  return static_cast<uint32_t>(best);
}

std::shared_ptr<const std::vector<uint32_t>> RealtimeLoop::lowered_pixels(std::vector<uint32_t> source) const {
  if (traced_pixels_)
    for (uint32_t& i : source) i = (*traced_pixels_)[i];
  return std::make_shared<const std::vector<uint32_t>>(std::move(source));
}

void RealtimeLoop::lower_in_place(uint64_t& kept_pixels) {
  const double scale = *lower_to_;
  lower_to_.reset();
  rebuild_.reset();
  const size_t big_w = static_cast<size_t>(params_.width), big_n = cast_.size();
  const glm::ivec2 size = scaled_size(requested_, scale);
  const size_t w = static_cast<size_t>(size.x), h = static_cast<size_t>(size.y), n = w * h;
  // Each smaller pixel's source: of the larger pixels whose nearest smaller pixel it is (its
  // footprint, one to a few), the one with the most rays, else the one nearest its centre. So every
  // larger pixel with rays that has no better neighbour survives, the coarse grid's included, and
  // the estimate of the pixels without rays keeps all it was made from (the nearest pixel alone
  // dropped about half of the grid at 70 % of the size, and the periphery's estimate changed by
  // 0.11–0.19 at its 99th percentile between the two frames). Footprints are disjoint and in pixel
  // order, and both axes shrink, so sources only grow with the index and never fall behind it
  // (source(i) >= i): each array is gathered in place, front to back, its memory kept (fresh arrays
  // for a view's ~110 bytes a pixel are tens of milliseconds of page faults)
  const Footprints footprints(big_w, big_n / big_w, w, h);
  std::vector<uint32_t>& source = order_;  // (scratch of the view's size: no fresh pages)
  source.resize(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, h, 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t y = r.begin(); y != r.end(); ++y)
      for (size_t x = 0; x < w; ++x) source[y * w + x] = footprints.source(x, y, *this);
  });
  traced_pixels_ = lowered_pixels(source);  // (a copy: the scratch is the loop's)
  auto gather = [&](auto& v) {
    if (v.size() != big_n) return;  // (not held for this view)
    for (size_t i = 0; i < n; ++i) v[i] = v[source[i]];
    v.resize(n);
  };
  GBuffer& g = gbuffer_;
  tbb::parallel_invoke([&] { gather(g.prim); }, [&] { gather(g.position); }, [&] { gather(g.normal); }, [&] { gather(g.geo_normal); },
                       [&] { gather(g.albedo); }, [&] { gather(g.depth); }, [&] { gather(g.view); }, [&] { gather(lit_); },
                       [&] { gather(ambient_); }, [&] { gather(ray_x_); }, [&] { gather(ray_y_); }, [&] { gather(ray_z_); },
                       [&] { gather(cast_); }, [&] { gather(open_); }, [&] { gather(kept_cast_); }, [&] { gather(kept_open_); },
                       [&] { gather(kept_origin_); });
  g.width = size.x;
  g.height = size.y;
  // The rays so far are kept, as a new view keeps those of the view before: each pixel's own were
  // another pixel's sequence, and this view's rays go on under a seed of its own. Rays that all left
  // the pixel's own surface point need no sum of their origins (kept_origin)
  if (!any_kept()) {
    kept_cast_.swap(counts_.cast);  // (memory an earlier view's counts left, where there is some)
    kept_open_.swap(counts_.open);
    kept_cast_.assign(n, 0.0f);
    kept_open_.assign(n, 0.0f);
    kept_origin_.clear();
  }
  const bool origins = !kept_origin_.empty();
  std::atomic<uint64_t> kept{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    uint64_t with_rays = 0;
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const float own = static_cast<float>(cast_[i]);
      kept_cast_[i] += own;
      kept_open_[i] += static_cast<float>(open_[i]);
      if (origins) kept_origin_[i] += own * g.position[i];
      with_rays += kept_cast_[i] > 0 ? 1 : 0;
    }
    kept += with_rays;
  });
  kept_pixels = kept;
  cast_.assign(n, 0);
  open_.assign(n, 0);
  ++views_;
  view_seed_ = scrambled_seed(params_.seed, views_);
  const double ratio = static_cast<double>(n) / static_cast<double>(big_n);  // (as adopt_rebuild)
  take_size(scale, size);
  finish_ms_ *= ratio;
  plan_ms_ *= ratio;
  sweep_.scale(ratio);
  narrow_sweep_.scale(ratio);
  estimate_cost_.scale(ratio);
  ++gbuffer_version_;
  renderer_.prepare_ao_batches(gbuffer_, gbuffer_version_);
  estimates_ = false;
  grid_pending_ = true;
  all_converged_ = false;
  prepare_rounds(n);
  maps_gaze_.reset();  // (the frame evaluates them at this size, from the eye rays gathered)
  for (Image& spare : spares_)
    if (spare.channels == 3 && spare.pixels.capacity() >= 3 * n) {  // a handed-back image's memory, for the frame's
      spare.width = size.x;
      spare.height = size.y;
      spare.pixels.resize(3 * n);
    }
}

void RealtimeLoop::start_rebuild(double scale, std::string why, bool lowering) {
  Rebuild r;
  r.scale = scale;
  r.why = std::move(why);
  r.lowering = lowering;
  const glm::ivec2 size = scaled_size(requested_, scale);
  r.width = size.x;
  r.height = size.y;
  // The view's memory reserved, not touched: each step touches only its own rows' pages (a whole
  // view's 70 bytes a pixel at once is tens of milliseconds of page faults)
  const size_t n = static_cast<size_t>(r.width) * static_cast<size_t>(r.height);
  r.gbuffer.width = r.width;
  r.gbuffer.height = r.height;
  for (auto* v : {&r.gbuffer.position, &r.gbuffer.normal, &r.gbuffer.geo_normal, &r.gbuffer.albedo, &r.gbuffer.view, &r.lit, &r.ambient})
    v->reserve(n);
  r.gbuffer.prim.reserve(n);
  r.gbuffer.depth.reserve(n);
  for (auto* v : {&r.ray_x, &r.ray_y, &r.ray_z, &r.maps.quality, &r.maps.eccentricity, &r.maps.blend, &r.kept.open, &r.kept.cast})
    v->reserve(n);
  r.kept.origin_sum.reserve(n);  // (grown row by row without it, its reallocations took 2–3 ms of a step, 1,500 page faults)
  r.maps.rays.reserve(n);
  r.maps.width = r.width;
  r.maps.height = r.height;
  for (Image& image : r.images) {
    image.width = r.width;
    image.height = r.height;
    image.channels = 3;
    image.pixels.reserve(3 * n);
  }
  r.gaze = measured_px_.value_or(glm::dvec2(requested_.width * 0.5, requested_.height * 0.5)) * scale;
  if (lowering) {
    r.stage = Rebuild::gather;
    r.footprints = Footprints(static_cast<size_t>(params_.width), static_cast<size_t>(params_.height), static_cast<size_t>(r.width),
                              static_cast<size_t>(r.height));
    r.source.reserve(n);
    if (traced_pixels_) r.traced.reserve(n);
  }
  rebuild_ = std::move(r);
}

void RealtimeLoop::advance_rebuild(const Timer& frame_timer, double until_ms, int& rows_left, glm::dvec2 gaze_px) {
  Rebuild& r = *rebuild_;
  const size_t w = static_cast<size_t>(r.width);
  for (bool first = true; r.stage != Rebuild::done && rows_left > 0; first = false) {
    if (r.stage == Rebuild::refresh_maps && r.row == 0) {  // (the gaze the maps are evaluated at, where it has moved far enough)
      const glm::dvec2 gaze = gaze_px * r.scale;
      const double ppd = pixels_per_degree(params_.display) * r.width / params_.display.res_x;
      if (glm::length(gaze - r.gaze) <= kMapsStaleDeg * ppd) {
        r.stage = Rebuild::done;
        break;
      }
      r.gaze = gaze;
    }
    const double left = until_ms - frame_timer.ms();
    if (left <= 0 && !first) return;  // (a step a frame at least)
    if (r.stage == Rebuild::keep && !settings_.keep_history) {
      r.stage = Rebuild::done;
      break;
    }
    // Rows for half a millisecond, or half of what is left of the time (one row at a stage's
    // start): a step's pace varies with what its rows hold (a reprojection step measured up to
    // 2.5× its estimate), and a step started near the deadline would end past it. The rays kept are
    // the view at hand's rows, the other stages the view built's
    const int height = r.stage == Rebuild::keep            ? params_.height
                       : r.stage == Rebuild::estimate      ? PullPush::first_rows(r.height)  // (the pyramid's first level)
                       : r.stage == Rebuild::estimate_push ? 1
                                                           : r.height;
    const int rows = std::clamp(r.rows_per_ms > 0 ? static_cast<int>(r.rows_per_ms * std::clamp(0.5 * left, 0.0, 0.5)) : 1, 1,
                                std::min(height - r.row, rows_left));
    const Timer step;
    const size_t b = static_cast<size_t>(r.row) * w;
    int got = rows;
    if (r.stage == Rebuild::surfaces) {
      const GBuffer part = renderer_.surfaces_rows(camera_, r.width, r.height, r.row, r.row + rows);
      got = part.height;
      append_rows(r.gbuffer, part);
    } else if (r.stage == Rebuild::shading) {  // the shading, the eye rays and the maps at the gaze
      const size_t e = b + static_cast<size_t>(rows) * w;
      for (auto* v : {&r.lit, &r.ambient}) v->resize(e);
      for (Image& image : r.images) image.pixels.resize(3 * e);  // (their pages touched here, a few at a time: 5 MB at once took 2.5 ms)
      for (auto* v : {&r.ray_x, &r.ray_y, &r.ray_z, &r.maps.quality, &r.maps.eccentricity, &r.maps.blend}) v->resize(e);
      r.maps.rays.resize(e);
      shade(r.gbuffer, camera_, b, e, r.lit, r.ambient);
      const FoveationModel model(params_.display, r.width, r.height, r.gaze, params_.foveation);
      tbb::parallel_for(tbb::blocked_range<size_t>(b, e, 4096), [&](const tbb::blocked_range<size_t>& range) {
        eye_rays(model, w, range.begin(), range.end(), r.ray_x.data(), r.ray_y.data(), r.ray_z.data());
        evaluate_maps(model, params_.foveation, params_.mode == RenderMode::foveated, r.ray_x.data(), r.ray_y.data(), r.ray_z.data(),
                      range.begin(), range.end(), r.maps);
      });
    } else if (r.stage == Rebuild::gather) {
      // A lowered size's rows, from the view at hand (lower_in_place's rule): each pixel's surface
      // point, shading and eye ray its larger pixel's, the maps evaluated at the gaze
      const size_t e = b + static_cast<size_t>(rows) * w;
      r.source.resize(e);
      if (traced_pixels_) r.traced.resize(e);
      GBuffer& g = r.gbuffer;
      g.prim.resize(e);
      g.depth.resize(e);
      for (auto* v : {&g.position, &g.normal, &g.geo_normal, &g.albedo, &g.view, &r.lit, &r.ambient}) v->resize(e);
      for (Image& image : r.images) image.pixels.resize(3 * e);
      for (auto* v : {&r.ray_x, &r.ray_y, &r.ray_z, &r.maps.quality, &r.maps.eccentricity, &r.maps.blend}) v->resize(e);
      r.maps.rays.resize(e);
      const FoveationModel model(params_.display, r.width, r.height, r.gaze, params_.foveation);
      tbb::parallel_for(tbb::blocked_range<size_t>(b, e, 2048), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
          const uint32_t from = r.footprints.source(i % w, i / w, *this);
          r.source[i] = from;
          if (traced_pixels_) r.traced[i] = (*traced_pixels_)[from];
          g.prim[i] = gbuffer_.prim[from];
          g.position[i] = gbuffer_.position[from];
          g.normal[i] = gbuffer_.normal[from];
          g.geo_normal[i] = gbuffer_.geo_normal[from];
          g.albedo[i] = gbuffer_.albedo[from];
          g.depth[i] = gbuffer_.depth[from];
          g.view[i] = gbuffer_.view[from];
          r.lit[i] = lit_[from];
          r.ambient[i] = ambient_[from];
          r.ray_x[i] = ray_x_[from];
          r.ray_y[i] = ray_y_[from];
          r.ray_z[i] = ray_z_[from];
        }
        evaluate_maps(model, params_.foveation, params_.mode == RenderMode::foveated, r.ray_x.data(), r.ray_y.data(), r.ray_z.data(),
                      range.begin(), range.end(), r.maps);
      });
    } else if (r.stage == Rebuild::gather_rays) {
      // … and their rays so far, kept as a new view keeps the view before's (lower_in_place): as late
      // as the view is built, since the larger view's frames go on casting them
      const size_t e = b + static_cast<size_t>(rows) * w;
      r.kept.open.resize(e);
      r.kept.cast.resize(e);
      r.kept.origin_sum.resize(e);
      std::atomic<uint64_t> kept{0};
      tbb::parallel_for(tbb::blocked_range<size_t>(b, e, 4096), [&](const tbb::blocked_range<size_t>& range) {
        uint64_t with_rays = 0;
        for (size_t i = range.begin(); i != range.end(); ++i) {
          pixel_counts(r.source[i], r.gbuffer.position[i], r.kept.open[i], r.kept.cast[i], r.kept.origin_sum[i]);
          with_rays += r.kept.cast[i] > 0 ? 1 : 0;
        }
        kept += with_rays;
      });
      r.kept_pixels += kept;
    } else if (r.stage == Rebuild::estimate) {
      // The pixels without rays, estimated from the rays kept (as estimate_unreached does, where
      // this view's own are none yet): the pyramid's first level, by rows of it
      if (r.row == 0) r.pull_push.prepare(r.width, r.height);
      const bool kept = r.kept_pixels > 0;
      r.unreached = pull_unreached(
                        r.pull_push, r.gbuffer, r.maps, [&](size_t i) { return kept ? r.kept.cast[i] : 0.0f; },
                        [&](size_t i) { return r.kept.open[i]; }, r.row, r.row + rows) ||
                    r.unreached;
    } else if (r.stage == Rebuild::refresh_maps) {
      const size_t e = b + static_cast<size_t>(rows) * w;
      const FoveationModel model(params_.display, r.width, r.height, r.gaze, params_.foveation);
      tbb::parallel_for(tbb::blocked_range<size_t>(b, e, 4096), [&](const tbb::blocked_range<size_t>& range) {
        evaluate_maps(model, params_.foveation, params_.mode == RenderMode::foveated, r.ray_x.data(), r.ray_y.data(), r.ray_z.data(),
                      range.begin(), range.end(), r.maps);
      });
    } else if (r.stage == Rebuild::estimate_push) {
      r.pull_push.pull_levels();
      r.estimated = true;
      r.pushed = r.unreached && r.pull_push.push();
      ++estimates_made_;
    } else if (r.stage == Rebuild::keep) {
      // The view at hand's rays, kept for the view built to take over, row by row: at once, its
      // surfaces and counts copied (about 45 bytes a pixel), they took 6–17 ms of a frame at 616×385
      // on two cores, page faults included, where the budget was 8 ms
      if (r.row == 0) history_.begin_rows(params_.width, params_.height, camera_);
      history_.store_rows(
          gbuffer_, maps_, params_.reuse,
          [&](size_t i, glm::vec3 position, float& open, float& cast, glm::vec3& origin_sum) {
            pixel_counts(i, position, open, cast, origin_sum);
          },
          r.row, r.row + rows);
    } else {  // reproject: the rays kept, row by row
      const size_t e = b + static_cast<size_t>(rows) * w;
      r.kept.open.resize(e);
      r.kept.cast.resize(e);
      r.kept.origin_sum.resize(e);
      r.kept_pixels += history_.reproject_rows(r.gbuffer, r.maps, params_.reuse, r.kept, r.row, r.row + rows);
    }
    const double ms = step.ms();
    if (ms > 0.05) r.rows_per_ms = r.rows_per_ms > 0 ? 0.5 * r.rows_per_ms + 0.5 * got / ms : got / ms;
    r.row += got;
    rows_left -= got;
    if (r.row < height) continue;
    r.row = 0;
    r.rows_per_ms = 0;
    r.stage = r.stage == Rebuild::surfaces        ? Rebuild::shading
              : r.stage == Rebuild::shading       ? Rebuild::keep
              : r.stage == Rebuild::keep          ? Rebuild::reproject
              : r.stage == Rebuild::reproject     ? Rebuild::estimate
              : r.stage == Rebuild::gather        ? Rebuild::gather_rays
              : r.stage == Rebuild::gather_rays   ? Rebuild::estimate
              : r.stage == Rebuild::estimate      ? Rebuild::estimate_push
              : r.stage == Rebuild::estimate_push ? Rebuild::refresh_maps
                                                  : Rebuild::done;
  }
}

void RealtimeLoop::adopt_rebuild(uint64_t& kept_pixels) {
  Rebuild& r = *rebuild_;
  const double pixels_before = static_cast<double>(std::max<size_t>(1, cast_.size()));
  take_size(r.scale, glm::ivec2(r.width, r.height));
  gbuffer_ = std::move(r.gbuffer);
  ++gbuffer_version_;
  renderer_.prepare_ao_batches(gbuffer_, gbuffer_version_);
  // A size grown back was traced; a lowered one's pixels of the view traced last were gathered with it
  if (!r.lowering) {
    traced_size_ = glm::ivec2(r.width, r.height);
    traced_pixels_.reset();
  } else {
    traced_pixels_ = std::make_shared<const std::vector<uint32_t>>(traced_pixels_ ? std::move(r.traced) : std::move(r.source));
  }
  lit_ = std::move(r.lit);
  ambient_ = std::move(r.ambient);
  ray_x_ = std::move(r.ray_x);
  ray_y_ = std::move(r.ray_y);
  ray_z_ = std::move(r.ray_z);
  maps_ = std::move(r.maps);
  maps_gaze_ = maps_full_gaze_ = r.gaze;
  maps_box_ = glm::ivec4(0, 0, r.width, r.height);
  reached_ = true;
  all_converged_ = false;
  collect_fovea(r.gaze, false);
  const size_t n = gbuffer_.prim.size();
  cast_.assign(n, 0);
  open_.assign(n, 0);
  estimates_ = false;  // (those of the view before)
  unreached_possible_ = true;
  if (r.estimated) {  // (made by rows: estimate_unreached makes the next when due)
    std::swap(pull_push_, r.pull_push);
    unreached_possible_ = r.unreached;
    estimates_ = r.pushed;
    estimate_age_ = 0;
    reached_ = false;
  }
  grid_pending_ = true;
  prepare_rounds(n);  // (the pyramid's memory: already this size where the estimate was made)
  kept_pixels = r.kept_pixels;
  if (kept_pixels > 0) {
    kept_open_ = std::move(r.kept.open);
    kept_cast_ = std::move(r.kept.cast);
    kept_origin_ = std::move(r.kept.origin_sum);
  } else {
    kept_open_.clear();
    kept_cast_.clear();
    kept_origin_.clear();
  }
  ++views_;
  view_seed_ = any_kept() ? scrambled_seed(params_.seed, views_) : params_.seed;
  spares_ = std::move(r.images);
  // What composing, planning the fovea and sweeping the periphery take goes with the pixels (the
  // smaller view's sweep estimate let the first full-size sweep run 4 ms past the deadline)
  const double ratio = static_cast<double>(n) / pixels_before;
  finish_ms_ *= ratio;
  plan_ms_ *= ratio;
  sweep_.scale(ratio);
  narrow_sweep_.scale(ratio);
  estimate_cost_.scale(ratio);
  if (r.lowering) {
    note_ = r.why;  // (rescale's; a size lowered for a still view is no size a camera at rest gets back)
  } else {
    note_ = size_note(r.why.c_str());
    motion_scale_.reset();
  }
  fixed_.clear();
  rebuild_.reset();
}

LoopFrame RealtimeLoop::frame(const Camera& camera) {
  const Timer timer;
  LoopFrame out;
  out.index = index_++;
  // The chunks the frame before left to paused threads: ended by now, most often (its tasks and
  // surfaces change from here on)
  if (const AoLeftBehind::Finished left = left_behind_.finish(); left.chunks > 0)
    out.left_behind_ms = std::max(0.0, std::chrono::duration<double, std::milli>(left.last - left_at_).count());
  double view_ms = 0;
  const bool moved = have_view_ && !same_camera(camera, camera_);
  if (moved) rebuild_.reset();                                     // (a size coming back for the view before)
  if (lower_to_ && (!have_view_ || moved)) set_scale(*lower_to_);  // (a view to trace anyway: at the lower size)
  if (settings_.clock == LoopClock::wall && moved) {
    // The camera moves: where its view at this size would take more than the frame leaves (the
    // view before's cost where views follow one another, else the cost per pixel measured), render
    // smaller before tracing it, else this frame is late
    const double per_px = !settings_.keep_history     ? fresh_view_ms_per_px_  // (no rays to keep)
                          : moved_view_ms_per_px_ > 0 ? moved_view_ms_per_px_
                                                      : kCarryCost * fresh_view_ms_per_px_;
    const double predicted = last_new_view_ ? last_view_cost_ms_ : per_px * static_cast<double>(params_.width) * params_.height;
    if (predicted > settings_.budget_ms - loop_margin_ms(settings_) - finish_ms_) {
      const double scale_before = scale_;
      if (rescale(predicted) && !motion_scale_) motion_scale_ = scale_before;
      fixed_.clear();
    }
  }
  if (!have_view_ || moved) {
    const Timer view_timer;
    const bool carried = new_view(camera, out.kept_pixels);
    view_ms = view_timer.ms();
    out.new_view = true;
    (carried ? moved_view_ms_per_px_ : fresh_view_ms_per_px_) = view_ms / (static_cast<double>(params_.width) * params_.height);
  } else if (lower_to_) {
    const Timer lower_timer;
    lower_in_place(out.kept_pixels);
    view_ms = lower_timer.ms();
    out.new_view = out.lowered = true;
  } else if (rebuild_ && rebuild_->stage == Rebuild::done) {
    out.lowered = rebuild_->lowering;
    adopt_rebuild(out.kept_pixels);
    out.new_view = true;
  }
  // Where the fovea goes: the predicted landing while a saccade flies, else the measured gaze
  const glm::dvec2 centre(requested_.width * 0.5, requested_.height * 0.5);
  glm::dvec2 gaze = measured_px_.value_or(centre);
  out.measured_px = gaze * scale_;
  const LandingState& flight = predictor_.state();
  out.in_flight = flight.in_flight;
  if (settings_.predict && flight.in_flight) {
    gaze = glm::clamp(known_landing_px_.value_or(deg_to_px(flight.landing_deg)), glm::dvec2(0.0),
                      glm::dvec2(requested_.width, requested_.height));
    out.predicted = true;
  }
  out.gaze_px = gaze * scale_;
  const bool wall = settings_.clock == LoopClock::wall;
  // The margin: at least the settings', more where frames have lately ended later than planned
  const double margin = std::max(loop_margin_ms(settings_), slip_ms_);  // (slip_ms_ at most a quarter of the budget)
  double deadline = settings_.budget_ms - margin - finish_ms_;
  const Timer maps_timer;
  update_maps(out.gaze_px, out.predicted);
  out.estimate_deferred = estimate_unreached(wall ? deadline - timer.ms() : std::numeric_limits<double>::infinity());
  out.maps_ms = maps_timer.ms();
  // A size held at min_scale whose base shading leaves its rays no time: the frame is late anyway,
  // and its rays get kHeldRaysShare of the budget after it, so that its AO still refines (else no
  // frame traced a ray, and the image kept the constant ambient term for good)
  const double model_fixed = settings_.model_fixed_ms * scale_ * scale_;  // the model's fixed cost scales with the pixels
  const bool held = held_note_.has_value() && (wall ? deadline <= timer.ms() : model_fixed >= settings_.budget_ms);
  if (held && wall) deadline = timer.ms() + plan_ms_ + kHeldRaysShare * settings_.budget_ms;  // (a round planned, then its rays)
  // AO rays, in rounds, within what the frame may spend on them
  double trace_ms = 0, sweep_ms = 0;
  // The periphery's rays stop at their share of the budget (1: at the deadline): a frame that ends
  // early is not made late by a pause of the machine's (a held size's share the fovea's rays)
  const double periphery_deadline = held ? deadline : std::min(deadline, settings_.periphery_share * settings_.budget_ms - finish_ms_);
  // The rays ahead of the gaze stop at their share of it (plan_ahead)
  const double ahead_deadline = std::min(periphery_deadline, kAheadShare * settings_.budget_ms - finish_ms_);
  // A size coming back: half of what is left before the deadline builds it (the rest after the
  // rays, if they leave any)
  int rebuild_rows = settings_.rebuild_rows_per_frame.value_or(std::numeric_limits<int>::max());
  auto rebuild = [&](double until_ms) {
    if (!rebuild_ || rebuild_->stage == Rebuild::done || rebuild_rows <= 0) return;
    const Timer rebuild_timer;
    advance_rebuild(timer, until_ms, rebuild_rows, gaze);
    out.rebuilding = true;
    out.rebuild_ms += rebuild_timer.ms();
    out.rebuild_width = rebuild_->width;
    out.rebuild_height = rebuild_->height;
  };
  if (wall) rebuild(timer.ms() + 0.5 * (deadline - timer.ms()));
  out.deadline_ms = deadline;
  out.compose_planned_ms = finish_ms_;
  auto model_rays = [&](double ms) { return static_cast<uint64_t>(std::max(0.0, (ms - model_fixed) * settings_.model_rays_per_ms)); };
  const auto held_rays = static_cast<uint64_t>(kHeldRaysShare * settings_.budget_ms * settings_.model_rays_per_ms);
  uint64_t allowance = wall ? 0 : held ? held_rays : model_rays(settings_.budget_ms);
  const uint64_t periphery_allowance = wall ? 0 : held ? allowance : model_rays(settings_.periphery_share * settings_.budget_ms);
  // (A new view's frame casts none: a view starts unconverged, and the frame whose sweep finds every
  // pixel converged ends its rays there, so the rays ahead begin with the next frame of the same
  // view; a moving camera's next view is another)
  const uint64_t ahead_allowance =
      wall || !settings_.rays_ahead ? 0 : model_rays(std::min(kAheadShare, settings_.periphery_share) * settings_.budget_ms);
  bool ran_out = false;  // the rays stopped for want of work, not for the deadline
  for (;;) {
    uint64_t limit = allowance, periphery_limit = 0, ahead_limit = 0;  // (0: no periphery, no rays ahead this round)
    if (wall) {
      const double left = deadline - timer.ms() - plan_ms_;
      if (left <= 0) break;
      auto rays_in = [&](double ms) { return rays_per_ms_ > 0 ? static_cast<uint64_t>(rays_per_ms_ * ms * 1.5) + 1024 : 65536; };
      limit = rays_in(left);
      // A periphery round sweeps every pixel: only when its planning fits
      const double periphery_left = periphery_deadline - timer.ms() - plan_ms_;
      if (next_sweep().fits(periphery_left)) periphery_limit = std::min(limit, rays_in(periphery_left));
      const double ahead_left = ahead_deadline - timer.ms() - plan_ms_;
      if (settings_.rays_ahead && next_sweep().fits(ahead_left)) ahead_limit = std::min(limit, rays_in(ahead_left));
    } else {
      if (allowance == 0) break;
      periphery_limit = std::min(allowance, periphery_allowance - std::min(periphery_allowance, out.rays));
      ahead_limit = std::min(allowance, ahead_allowance - std::min(ahead_allowance, out.rays));
    }
    const bool periphery = periphery_limit > 0;
    SweepCost& sweep_cost = next_sweep();  // (what a sweep in this round costs: wide or narrow)
    const Timer plan_timer;
    Round round;
    const size_t planned = plan_round(limit, periphery_limit, ahead_limit, round);
    const bool swept = round != Round::fovea;
    const double plan_ms = plan_timer.ms();
    out.plan_ms += plan_ms;
    if (swept) {  // a pass over every pixel
      ++out.sweeps;
      sweep_cost.swept(plan_ms);
      sweep_ms += plan_ms;
    } else {
      plan_ms_ = 0.7 * plan_ms_ + 0.3 * plan_ms;
    }
    if (planned == 0) {
      // (nothing for the fovea, and the periphery's sweep did not fit: try it again a little sooner)
      if (wall && !periphery && periphery_deadline - timer.ms() > 0) sweep_cost.skipped();
      ran_out = periphery;  // every pixel had its rays
      break;
    }
    blocked_.resize(tasks_.size());
    done_.resize(tasks_.size());
    AoRayBatch batch;
    batch.gbuffer = &gbuffer_;
    batch.gbuffer_version = gbuffer_version_;
    batch.ao_distance = ao_distance_;
    batch.epsilon = epsilon_;
    batch.seed = view_seed_;
    batch.tasks = tasks_;
    batch.blocked = blocked_;
    batch.done = done_;
    batch.slowdown = settings_.slowdown;
    const double until = round == Round::ahead ? ahead_deadline : swept ? periphery_deadline : deadline;
    if (wall) {
      batch.expired = [&] { return timer.ms() >= until; };
      batch.leave_behind_after_ms = kLeaveBehindAfterMs;
      batch.left_behind = &left_behind_;
    }
    const Timer trace_timer;
    const uint64_t traced = renderer_.trace_ao_batch(batch);
    if (left_behind_.pending() > 0) {
      out.chunks_left_behind += left_behind_.pending();
      left_at_ = std::chrono::steady_clock::now();
    }
    const double ms = trace_timer.ms();
    trace_ms += ms;
    out.rays += traced;
    for (size_t t = 0; t < tasks_.size(); ++t)
      if (done_[t]) {
        if (!reached_ && tasks_[t].count > 0 && maps_.quality[tasks_[t].pixel] < 1.0f && total_cast(tasks_[t].pixel) == 0) reached_ = true;
        cast_[tasks_[t].pixel] += tasks_[t].count;
        open_[tasks_[t].pixel] += tasks_[t].count - blocked_[t];
        periphery_keys_.stale(tasks_[t].pixel);
        ahead_keys_.stale(tasks_[t].pixel);
      }
    if (wall && traced > 0 && ms > 0.2) {
      const double rate = static_cast<double>(traced) / ms;
      rays_per_ms_ = rays_per_ms_ > 0 ? 0.7 * rays_per_ms_ + 0.3 * rate : rate;
    }
    if (!wall) allowance -= std::min(allowance, traced);
    if (traced == 0 || left_behind_.pending() > 0) break;  // (planning another round would change the tasks those chunks read)
  }
  if (wall && rebuild_ && timer.ms() < deadline - 1) rebuild(deadline);
  // The image, and the fovea's state
  out.rays_end_ms = timer.ms();
  const Timer finish_timer;
  compose(out.color);
  out.scale = scale_;
  out.compose_ms = finish_timer.ms();
  size_t done = 0;
  for (const uint32_t i : fovea_) done += converged(i) ? 1 : 0;
  out.fovea_converged = fovea_.empty() ? 1.0 : static_cast<double>(done) / static_cast<double>(fovea_.size());
  out.fovea_done = done == fovea_.size();
  finish_ms_ = std::max(0.8 * finish_ms_ + 0.2 * finish_timer.ms(), finish_timer.ms());  // what the frame's end takes, at least the last
  out.ms = timer.ms();
  out.trace_ms = trace_ms;
  out.cost_ms = wall ? out.ms : model_fixed + static_cast<double>(out.rays) / settings_.model_rays_per_ms;
  out.late = out.cost_ms > settings_.budget_ms;
  if (wall && !out.new_view) {
    // How much later than planned the frame ended (the machine's pauses: a thread descheduled, page
    // faults), kept as a slowly decaying maximum (halved in ~2 s at 60 Hz): the margin for the
    // next frames. A fixed 2 ms left 1–4 frames in 600 late on a shared 2-core VM. (A new view's
    // surfaces are no slip: a moving camera's frames are made smaller instead, rescale.)
    const double slip = out.ms - (settings_.budget_ms - margin);
    slip_ms_ = std::min(std::max(slip_ms_ * kSlipDecay, slip + kSlipPad), 0.25 * settings_.budget_ms);
  }
  // Where the frame's fixed part alone (surfaces, maps, composing) takes most of the budget, the
  // next frames render smaller
  // (a new view counts when views follow one another: a moving camera; a still one pays it once)
  // (a size lowered in place traces nothing: no view for a camera that moves next to be judged by)
  const bool moving = out.new_view && !out.lowered && last_new_view_;
  last_new_view_ = out.new_view && !out.lowered;
  // (planning the periphery is no fixed part either: the loop sweeps it only when the sweep fits, and
  // on a 2-core AMD EPYC VM its 3–5 ms with maps and composing passed 60 % of the budget and
  // lowered the resolution while the fovea was converged)
  const double fixed = !wall                     ? model_fixed
                       : settings_.fixed_part_ms ? *settings_.fixed_part_ms * scale_ * scale_
                                                 : out.ms - trace_ms - sweep_ms - out.rebuild_ms - (moving ? 0.0 : view_ms);
  last_view_cost_ms_ = out.new_view ? out.ms - trace_ms - sweep_ms - out.rebuild_ms : 0;  // a new view's fixed part, its surfaces included
  // (on the wall clock over five frames at least: a first frame's page faults, one frame's pause,
  // are no reason. A camera that moves on after a view costlier than the whole budget is, at once:
  // the next frame's start lowers the size before it traces its view; waiting for five frames made
  // four more late by 80–115 ms each, orbiting the dragon at 840×525 on a 2-core VM)
  const double scale_before = scale_;
  if (fixed_.add(fixed, settings_.budget_ms, wall ? 5 : 1)) {
    // (a still view's smaller size is taken from it at the next frame; a moving camera's next view is
    // traced at that size anyway)
    if (rescale(fixed_.median_ms(), !moving)) {
      if (moving && !motion_scale_) motion_scale_ = scale_before;  // the size to return to at rest
      if (!moving) lowered_still(out.index);
    }
    fixed_.clear();
  } else if (wall && rebuild_ && rebuild_->lowering && fixed > settings_.budget_ms) {
    // A lower size under way whose larger view's frame was late for its fixed part alone (the budget
    // fell since: an experiment's own work took more of the refresh) is taken at the next frame, at
    // once: in the PsychoPy example under Xvfb the budget fell from 5–6 to 4 ms while it was built,
    // and four frames at the larger size came late by 0.3–1.8 ms before it was shown
    lower_to_ = rebuild_->scale;
    note_ = std::move(rebuild_->why);
    rebuild_.reset();
  }
  if (held_note_ && fixed_.size() >= (wall ? FixedPartWindow::kFrames : 1) && fixed_.median_ms() <= 0.6 * settings_.budget_ms)
    held_note_.reset();  // (the base shading fits again at the size held)
  // A moving camera whose frame ran out of work before its deadline grows towards the size it had
  // before it moved. The first moved view's size comes from an estimate (the first view's cost,
  // which pays the loop's first allocations), and a device whose views are cheap stayed at that
  // size until the camera rested (a third of 840x525 on a GPU whose frames then ended 8 ms before
  // the deadline). A frame's work (the view's surfaces, maps, the rays its pixels lack) grows with
  // its pixels, so the grown frame's fits in kGrowthShare of the time to the deadline and gives no
  // pixel fewer rays; a frame that traces until its deadline (a CPU's, mostly) does not grow.
  if (wall && moving && ran_out && motion_scale_ && scale_ == scale_before && out.rays_end_ms > 0) {
    const double target = std::min(*motion_scale_, scale_ * std::sqrt(kGrowthShare * deadline / out.rays_end_ms));
    if (target > kGrowth * scale_ || (target == *motion_scale_ && target > scale_)) {
      set_scale(target);
      const bool back = scale_ == *motion_scale_;
      if (back) motion_scale_.reset();  // nothing left to get back at rest
      note_ = size_note(back ? "the size before the camera moved" : "while the camera moves");
      fixed_.clear();
    }
  }
  // A still view made smaller for its fixed part grows back where that part would now fit: a budget
  // raised (an experiment that leaves the loop more of the refresh once its own first frames are
  // done), a busy spell of the machine's over. (Lowered once, a still view stayed small for good: a
  // PsychoPy session's first flips, which upload its window's first textures, left the loop 4 ms a
  // frame for a few frames, and 840x525 rendered at 85 % for the rest of the session at 8.8 ms.)
  // The grown view's fixed part takes half the budget by its pixels, below the 60 % that lowers it;
  // a part that does not shrink with the pixels makes that estimate high, not low.
  // On the wall clock the budget is the smallest of the latest frames' (kBudgetFrames).
  if (wall) budgets_.add(settings_.budget_ms);
  if (!out.new_view && !motion_scale_ && !rebuild_ && scale_ < 1 && fixed_.size() >= (wall ? FixedPartWindow::kFrames : 1)) {
    const double budget = wall ? budgets_.min() : settings_.budget_ms;
    const double target = std::min(1.0, scale_ * std::sqrt(0.5 * budget / fixed_.median_ms()));
    // (not while a size lowered again soon after it came back is held, the budget not grown: see
    // lowered_still)
    const bool held =
        lowered_still_ && out.index - lowered_still_->index < grow_hold_frames_ && budget < kHoldBudgetRise * lowered_still_->budget_ms;
    if (target > scale_ && (target == 1.0 || target >= kGrowth * scale_) && !held) {
      grow_back(target, "the base shading fits the budget again");
      grown_index_ = out.index;
    }
  }
  // A camera come to rest gets back the size it had before it moved, and the rays kept at the
  // smaller size carry over (a view stayed small for good once a camera had moved). On the wall
  // clock that view is built over the next frames (start_rebuild; traced at once, its surfaces
  // made the frame late by 50–90 ms at 840×525 on two cores); the model clock takes it at once.
  still_frames_ = out.new_view ? 0 : still_frames_ + 1;
  if (motion_scale_ && !rebuild_ && static_cast<double>(still_frames_) * settings_.budget_ms >= kRestMs)
    grow_back(*motion_scale_, "the size before the camera moved");
  return out;
}

void RealtimeLoop::lowered_still(int index) {
  // A still view lowered again within kFlapFrames of growing back waits longer before it grows
  // again (kFlapFrames, then twice as long each time, up to kMaxHoldFrames), unless the
  // budget grows by a quarter: with a budget of 4 ms at 840×525 on two cores the fixed part's median
  // sat about the 60 % that lowers the size, and the view came back and was lowered again every
  // 1.5–3 s, each time with a frame or two late (the one that lowers it, the one that takes the
  // larger view over)
  // (A view that stayed grown for kFlapFrames or longer was no flap: its hold starts afresh.)
  if (grown_index_ && index - *grown_index_ < kFlapFrames)
    grow_hold_frames_ = grow_hold_frames_ == 0 ? kFlapFrames : std::min(2 * grow_hold_frames_, kMaxHoldFrames);
  else
    grow_hold_frames_ = 0;
  lowered_still_ = LoweredStill{index, settings_.budget_ms};
}

void RealtimeLoop::grow_back(double scale, const char* why) {
  if (settings_.clock == LoopClock::wall) {
    start_rebuild(scale, why);  // adopted once built (adopt_rebuild)
    return;
  }
  set_scale(scale);
  note_ = size_note(why);
  motion_scale_.reset();
  fixed_.clear();
}

}  // namespace foveal
