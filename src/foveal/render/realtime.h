// foveal/render/realtime.h — gaze-contingent rendering against a deadline: a frame every refresh.
//
// A RealtimeLoop turns the renderer's whole-frame passes into a loop that a display can follow.
// Every call to frame() returns within the frame budget (1/refresh rate) an image of the whole
// view: the base shading, complete every frame, with the ambient occlusion accumulated so far.
//
// - The view's surfaces (the G-buffer) and the shading that does not depend on AO are computed once
//   per camera: with a still camera a frame only adds AO rays and recomposes. Eq. 2's ambient term
//   is linear in k_a, so the colour is S + k_a·A per pixel, S and A kept.
// - Each pixel keeps its AO rays across frames (open and cast counts) and continues its own Sobol
//   sequence, so n rays over many frames are exactly the paper's pixel's first n rays.
// - Inside the budget, rays go where they lower the perceived error most: first the pixels of the
//   fovea (q(E) = 1) not yet converged — at a new view with a coarse grid over the rest (every
//   16th pixel: its rays stand for the pixels around it, which show their estimate until they
//   have rays of their own) — then the rest in order of the q(E)²-weighted variance their next
//   rays remove (σ̂²·k/(c + k) from each pixel's own running estimate). A fovea pixel
//   is converged with its n_max rays (the reference's); a peripheral one once its standard error
//   is within τ(E) (issue 21's threshold, AoReuseParams::tolerance) or it has its n(E) rays. Rays
//   come in rounds that double a pixel's count, so a peripheral pixel whose rays all agree stops
//   early (adaptive sampling); the periphery fills in over frames.
// - With prediction on, while a saccade is in flight the fovea is placed at its predicted landing
//   (gaze/landing.h): the eye sees little during the flight (saccadic suppression), and the rays
//   are ready where it lands. Once the eye has landed the measured gaze is used again, so a wrong
//   prediction costs only the rays of the flight.
// - A moving camera keeps the AO of the surfaces it still sees: at a new view each pixel's rays
//   so far (open and cast counts, with the mean of their origins) are reprojected into the new
//   view as the renderer's temporal history does (reuse.h: the same surface, bilinear, weighed down
//   where the rays' mean origin drifts beyond what the eye resolves; a disocclusion starts afresh),
//   and the pixel goes on from there with a sequence scrambled for the view. A still camera keeps
//   every ray as is (the view is traced once).
// - The clock: `wall` casts rays until the deadline (the frame's remaining time minus what
//   composing takes) and checks it between chunks of about a thousand rays; `model` casts as many
//   rays as a fixed cost model allows, so that a run is the same whatever the machine's load (the
//   simulated clock of `bench latency` and the tests).
// - Where even the base shading does not fit the budget, the loop renders at a lower resolution
//   (scale() < 1, note() says so); the caller shows the image scaled up. A camera that starts to
//   move is rendered smaller at once where its view would not fit (each view's cost per pixel is
//   measured), and one at rest gets its size back through a view built a few rows at a time in
//   what the frames leave, shown once complete: neither makes a frame late.
#pragma once

#include "foveal/gaze/landing.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/render/pull_push.h"
#include "foveal/render/render.h"
#include "foveal/render/reuse.h"
#include "foveal/render/sweep_keys.h"
#include "foveal/util/stats.h"
#include "foveal/util/timer.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

enum class LoopClock { wall, model };
const char* to_string(LoopClock clock);
LoopClock parse_loop_clock(const std::string& name);  // throws Error naming --clock

inline constexpr double kDefaultPeripheryShare = 1.0;
inline constexpr double kDefaultMinScale = 0.25;
struct LoopSettings {
  double budget_ms = 1000.0 / 60;  // a frame every refresh
  bool predict = false;            // place the fovea at a saccade's predicted landing while it flies
  LandingParams landing;
  LoopClock clock = LoopClock::wall;
  double model_rays_per_ms = 0;  // model clock: AO rays per millisecond
  double model_fixed_ms = 0;     // model clock: a frame's cost besides its AO rays
  // Wall clock: kept free at the end of each frame for the machine's pauses. Unset: kDefaultMarginMs,
  // at most a quarter of the budget (so a short budget is not refused for a margin nobody asked for)
  std::optional<double> margin_ms;
  // The periphery's rays stop once the frame has spent this share of the budget (the fovea's go on
  // to the deadline): a frame that ends early is not made late by a pause of the machine's, at the
  // cost of the periphery's pace (docs/realtime.md). 1: the periphery's too go on to the deadline.
  // Both clocks (the model's: its rays up to the share)
  double periphery_share = kDefaultPeripheryShare;
  // The smallest resolution scale the loop may choose (1: the size asked for throughout, whose frames
  // come late where its base shading does not fit the budget; note() then says so)
  double min_scale = kDefaultMinScale;
  double slowdown = 1;  // tests only: the tracer this many times slower
  // Tests only: what an estimate of the pixels without rays is taken to cost on the wall clock,
  // instead of its measured time (RealtimeLoop::frame() leaves one that would pass the rays'
  // deadline to a later frame)
  std::optional<double> estimate_cost_ms;
  // Tests only: a frame's fixed part (what it costs besides its rays) taken to be this on the wall
  // clock at the full size, and less with the pixels, instead of its measured time
  std::optional<double> fixed_part_ms;
  // Tests only: the rows a frame may build of a view at another size at most (wall clock), so that
  // building it takes frames on any machine
  std::optional<int> rebuild_rows_per_frame;
  bool keep_history = true;  // a new view (the camera moved) keeps the AO of the surfaces it still sees
  // Once every pixel has its n(E), the frames' spare time raises the pixels towards n_max, nearest
  // the gaze first, within kAheadShare of each budget: where the eye lands next, its fovea finds
  // those rays (docs/realtime.md, "Rays ahead of the gaze"). false: a converged view casts nothing
  bool rays_ahead = true;
};
// The share of each frame's budget the rays ahead of the gaze may run to: frames that end early are
// not made late by the machine's pauses
inline constexpr double kAheadShare = 0.5;
// A size held at min_scale whose base shading leaves its rays no time: the share of the budget its
// frames' rays get after it (they are late anyway)
inline constexpr double kHeldRaysShare = 0.25;
// Wall clock: once a frame's rays are to stop, how long it waits for the chunks other threads are
// tracing (normally 10–40 µs each) before it leaves them behind: only a thread the
// machine has paused takes longer (AoRayBatch::leave_behind_after_ms)
inline constexpr double kLeaveBehindAfterMs = 0.25;
inline constexpr double kDefaultMarginMs = 2.0;
// The margin the settings keep: the given one, else the default within a quarter of the budget
double loop_margin_ms(const LoopSettings& settings);
// The same for a budget and a margin given or not
double loop_margin_ms(double budget_ms, std::optional<double> margin_ms);
// Check the settings; throws Error naming the option.
void validate(const LoopSettings& settings);

struct LoopFrame {
  int index = 0;
  Image color;                                      // linear RGB at the loop's render size (params().width × height)
  double scale = 1;                                 // that size as a share of the size asked for (scale() may be a next frame's)
  glm::dvec2 gaze_px{0};                            // where the fovea was placed, render pixels
  glm::dvec2 measured_px{0};                        // the latest measured gaze (render pixels; the image centre before any)
  bool predicted = false;                           // gaze_px is a predicted landing
  bool in_flight = false;                           // a saccade was under way at the latest sample
  uint64_t rays = 0;                                // AO rays traced this frame
  double ms = 0;                                    // wall time of frame()
  double trace_ms = 0;                              // of which tracing AO rays
  double maps_ms = 0, plan_ms = 0, compose_ms = 0;  // … the foveation maps, choosing rays, composing the image
  uint32_t sweeps = 0;                              // rounds that planned the periphery (each a pass over every pixel)
  // Wall clock, from the frame's start: when rays had to stop (the budget less the margin and the
  // frame's end planned), when they did, and the end planned (composing, the fovea's state): a late
  // frame's pause fell before rays stopped (rays_end_ms > deadline_ms) or into its end
  // (ms − rays_end_ms > compose_planned_ms)
  double deadline_ms = 0, rays_end_ms = 0, compose_planned_ms = 0;
  double cost_ms = 0;        // the frame's cost on the loop's clock (wall: ms; model: the model's)
  bool late = false;         // cost_ms > the budget
  bool new_view = false;     // the camera changed, or a size came back: surfaces traced (and AO kept where the view still sees them);
                             // or a still view's size was lowered (`lowered`)
  bool lowered = false;      // a still view's size lowered, taken from the view at hand: no surface traced (lower_in_place)
  uint64_t kept_pixels = 0;  // a new view: the pixels that kept AO rays from the view before
  bool rebuilding = false;   // part of the frame built the view at another size (larger, or lowered over frames)
  double rebuild_ms = 0;     // … in this much of the frame
  int rebuild_width = 0, rebuild_height = 0;  // … that size
  double fovea_converged = 0;                 // fraction of the fovea's (q = 1, hit) pixels whose AO is converged
  bool fovea_done = false;                    // all of them: the fovea is at full quality
  // Wall clock: chunks of this frame's rays left to threads the machine had paused, their rays
  // dropped, rather than waited for (kLeaveBehindAfterMs); and where the frame before left some,
  // how long after its rays stopped the last of them ended — how much later it would have ended had
  // it waited (NaN where it left none). This frame waited for any still running at its start, within
  // its own time
  uint32_t chunks_left_behind = 0;
  double left_behind_ms = NAN;
  // Wall clock: the estimate of the pixels without rays (pull-push) was due, but this frame had
  // no room for it before its rays' deadline — most often a frame that evaluated the maps at every
  // pixel — and it was left to a later frame that has room
  bool estimate_deferred = false;
};

// The median, or the least, of the latest N values (fewer before N have come).
template <size_t N>
class RecentMedian {
 public:
  void add(double value) {
    values_[next_] = value;
    next_ = (next_ + 1) % N;
    count_ = std::min(count_ + 1, N);
  }
  size_t size() const { return count_; }
  double median() const {  // NaN when empty
    return count_ == 0 ? NAN : foveal::median(std::vector<double>(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(count_)));
  }
  double min() const {  // NaN when empty
    return count_ == 0 ? NAN : *std::min_element(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(count_));
  }
  void clear() { count_ = next_ = 0; }

 private:
  std::array<double, N> values_{};
  size_t count_ = 0, next_ = 0;
};

// The loop's reason to render smaller: the fixed part of its frames (surfaces, maps, planning,
// composing: all but the rays) over the latest frames, judged by its median against 60 % of the
// budget — a sustained cost (a moving camera, a display too large), which one frame's pause does
// not make. (A mean of the frames before let a single 80 ms frame, a thread descheduled on a
// shared VM, lower the resolution for the rest of a run.)
class FixedPartWindow {
 public:
  static constexpr size_t kFrames = 8;
  // This frame's fixed part; true when the median of the latest frames (at least `min_frames` of
  // them) is above 60 % of the budget.
  bool add(double fixed_ms, double budget_ms, size_t min_frames);
  double median_ms() const { return latest_.median(); }
  size_t size() const { return latest_.size(); }  // frames in the window
  void clear() { latest_.clear(); }

 private:
  RecentMedian<kFrames> latest_;
};

// What a periphery round's planning (a pass over every pixel) costs on the wall clock, for the
// loop to sweep only where it fits before the deadline. A sweep's time raises the estimate at once
// (a sweep that does not fit makes the frame late); a frame that skips the sweep lowers it a little,
// down to the sweeps' typical cost, so that one sweep a pause lengthened does not stop the
// periphery's refinement for the rest of a run. (Raised and never lowered, the estimate stopped the
// sweeps for good on a shared 2-core VM: frames cost 1.5 ms at p50 where other runs spent 4 ms on
// rays, and landings on what had been periphery waited for rays.)
//
// Before the first sweep is timed its cost is unknown, and it is taken as half the frame's budget:
// the first sweep then starts only where a frame has that much left before its deadline. (Taken as
// 1 ms, the first sweep at 840×525 took 3.3–4.8 ms on a 2-core Intel Xeon VM: in 7 of 18 loops of
// `bench latency` on the dragon box it ended past the deadline, by up to 2.8 ms, and in 2 past the
// 2-ms margin too — that VM's only late frames while it was quiet.)
//
// The loop's estimate of the pixels without rays (estimate_unreached), another pass over every
// pixel that a frame without room leaves to a later one, keeps its cost the same way.
class SweepCost {
 public:
  static constexpr double kSkipDecay = 0.95;    // per frame that skips: from a pause's 30 ms to 12 in ~18 frames
  static constexpr size_t kSweeps = 5;          // the typical cost: the median of the latest sweeps
  static constexpr double kUntimedShare = 0.5;  // of the budget: the cost taken before a sweep is timed
  // The frame budget (ms): while no sweep has been timed, the estimate is kUntimedShare of it.
  void set_budget(double budget_ms) {
    if (!timed_) estimate_ms_ = kUntimedShare * budget_ms;
  }
  // Whether a sweep fits in the `left_ms` before the deadline.
  bool fits(double left_ms) const { return left_ms > estimate_ms_; }
  // A sweep took `ms`.
  void swept(double ms);
  // A frame did not sweep because it did not fit: the estimate falls a little, down to the latest
  // sweeps' median (freely before the first sweep, so that a budget whose frames never leave
  // kUntimedShare of it still gets its sweeps; not at all after a new size, until a sweep is timed)
  void skipped() {
    const double floor = !timed_ ? 0.0 : latest_.size() == 0 ? estimate_ms_ : latest_.median();
    estimate_ms_ = std::max(floor, kSkipDecay * estimate_ms_);
  }
  // The pixels changed by this factor (a new size): so does a sweep's cost
  void scale(double factor) {
    estimate_ms_ *= factor;
    latest_.clear();
  }
  double estimate_ms() const { return estimate_ms_; }
  bool timed() const { return timed_; }

 private:
  double estimate_ms_ = kUntimedShare * LoopSettings{}.budget_ms;  // (the loop sets its own: set_budget)
  bool timed_ = false;
  RecentMedian<kSweeps> latest_;
};

class RealtimeLoop {
 public:
  // `renderer` and `scene` must outlive the loop. params: size, display, foveation, seed, AO
  // distance, ambient constant (unset: auto, the mean visibility of the fovea's pixels with rays, as
  // the renderer's), reuse.tolerance (τ); the mode must be foveated.
  RealtimeLoop(FrameRenderer& renderer, const Scene& scene, const RenderParams& params, const LoopSettings& settings);

  // On the wall clock a still view made smaller grows back only where its fixed part fits the
  // smallest budget of the latest this many frames (2 s at 60 Hz): a budget that swings (an
  // experiment's own work varying from flip to flip) made the size go down and back up every second
  // or so, each time with late frames
  static constexpr size_t kBudgetFrames = 120;
  // A sample more than this older than the latest is a clock that restarted (a trial clock reset, a
  // tracker reconnected), not a sample out of order
  static constexpr double kClockRestartS = 0.5;
  // A tracker sample: its time (seconds, the tracker's clock) and point in render pixels (unset or
  // NaN: lost); throws Error naming t_s where the time is not finite. Samples come in time order: a
  // repeated time, or one up to kClockRestartS older than the latest, is ignored (a tracker's
  // duplicate, two sources' samples interleaved); one older than that restarts the clock — the
  // sample is taken, the predictor starts afresh and gaze_note() says so (ignoring every sample
  // until the old clock's time came round again froze the fovea without a word).
  void push_gaze(double t_s, std::optional<glm::dvec2> gaze_px);
  // The latest sample's time taken (seconds; unset before the first)
  std::optional<double> latest_sample_s() const { return last_pushed_s_; }
  // The next frame for `camera`, within the budget.
  LoopFrame frame(const Camera& camera);
  // Hand back a frame's image once it is no longer shown: a later frame is composed into it instead
  // of a new one (fewer page faults, steadier frame times; the loop holds up to two, and has two
  // ready when a view starts, for its first frames). Optional.
  void recycle(Image&& image);
  // A landing known in advance, render pixels (bench latency's "deadline+oracle": each saccade's
  // true landing, for the most any predictor could gain): while a saccade is in flight and
  // prediction is on, the fovea goes there instead of the predicted landing. Unset: the prediction.
  void set_known_landing(std::optional<glm::dvec2> landing_px) { known_landing_px_ = landing_px; }
  // Forget the accumulated AO (the next frame starts afresh).
  void reset();
  // A new frame budget (an application that measures its own per-frame work leaves the loop the
  // rest of the refresh); throws Error naming budget_ms. A margin the settings gave is kept within
  // half of each budget set (of the margin given: a budget lowered once does not shrink it for good);
  // the default one stays within a quarter.
  void set_budget_ms(double budget_ms);

  const RenderParams& params() const { return params_; }  // at the render size in use
  const LoopSettings& settings() const { return settings_; }
  // render size / requested size (a still view's size once lowered, though its next frame takes it)
  double scale() const { return lower_to_.value_or(scale_); }
  // Why the resolution was lowered, or why it could not be lowered further (min_scale); "" if neither
  const std::string& note() const { return held_note_ ? *held_note_ : note_; }
  bool size_held() const { return held_note_.has_value(); }  // note() says the size is held at min_scale, its frames late
  // With prediction on: what the samples pushed leave the landing predictor ("" if it can follow
  // them in time): they come further apart than a saccade's onset can be seen (under 20 Hz, as the
  // median of the latest intervals), most often times given in milliseconds where seconds are asked
  // for (an EyeLink's own clock), which would leave every saccade unpredicted without a word; or so
  // far apart that a landing is known too late to gain much (under 90 Hz: late_landing_note); and
  // whether the samples' clock went back (push_gaze)
  std::string gaze_note() const;
  // The rate the valid samples come at: 1 / the median of the latest 16 intervals (what gaze_note
  // judges); 0 before two have come
  double gaze_sample_hz() const { return intervals_s_.size() ? 1 / intervals_s_.median() : 0.0; }
  const LandingPredictor& predictor() const { return predictor_; }
  // Per pixel: AO rays cast so far in this view and found open (the loop's state, for tests and
  // pictures), and the rays kept from the views before (reprojected: fractional; zero where none).
  const std::vector<uint32_t>& cast() const { return cast_; }
  const std::vector<uint32_t>& open() const { return open_; }
  const std::vector<float>& kept_cast() const { return kept_cast_; }
  const std::vector<float>& kept_open() const { return kept_open_; }
  const FoveationMaps& maps() const { return maps_; }
  const GBuffer& gbuffer() const { return gbuffer_; }
  // The view whose surfaces were traced last (for a new camera, a size grown back): its size, and
  // where the view in use was lowered from it (in place or over frames, each smaller pixel one of its
  // footprint's larger pixels: lower_in_place), the pixel of it whose surface point, shading and eye
  // ray each of its pixels shows (a view lowered again maps through the first); null where the view
  // in use is the one traced. (bench latency judges a frame against references traced at that size,
  // on the pixels it shows.)
  glm::ivec2 traced_size() const { return traced_size_; }
  std::shared_ptr<const std::vector<uint32_t>> traced_pixels() const { return traced_pixels_; }
  // How many estimates of the pixels without rays the loop has made (estimate_unreached; tests)
  uint64_t estimates_made() const { return estimates_made_; }
  // How many times a frame evaluated the maps at every pixel (update_maps; tests)
  uint64_t maps_everywhere() const { return maps_everywhere_; }
  bool has_estimate() const { return estimates_; }                   // an estimate for the pixels without rays is held (from rays so far)
  float estimate(size_t i) const { return pull_push_.estimate(i); }  // … pixel i's (where has_estimate())
  int frame_index() const { return index_; }                         // the next frame's index: the frames made so far
  // Whether pixel i's AO is converged (τ(E) or n(E) reached).
  bool converged(size_t i) const;
  // How many pixels' sweep buckets, kept between sweeps, differ from what they would be now (those
  // marked to be computed again aside; tests: they are marked wherever a pixel's rays or maps change)
  size_t sweep_keys_out_of_date() const;

 private:
  // Pixel i's bucket in the periphery's sweep (SweepKeys::kNone where converged) and in the rays ahead's
  int periphery_key(size_t i) const;
  int ahead_key(size_t i) const;
  // Pixel i's rays: this view's and those kept from the views before
  bool any_kept() const { return !kept_cast_.empty(); }
  float total_cast(size_t i) const { return static_cast<float>(cast_[i]) + (any_kept() ? kept_cast_[i] : 0.0f); }
  float total_open(size_t i) const { return static_cast<float>(open_[i]) + (any_kept() ? kept_open_[i] : 0.0f); }
  // Σ of pixel i's kept rays' origins, where it has kept rays (`position`: its surface point)
  glm::vec3 kept_origin(size_t i, glm::vec3 position) const { return kept_origin_.empty() ? kept_cast_[i] * position : kept_origin_[i]; }
  // (kept_pixels: the pixels that kept rays from the view before); whether it carried rays over
  bool new_view(const Camera& camera, uint64_t& kept_pixels);
  // S and A of the colour S + k_a·A for pixels [b, e) of surfaces `g` seen from `camera`
  void shade(const GBuffer& g, const Camera& camera, size_t b, size_t e, std::vector<glm::vec3>& lit,
             std::vector<glm::vec3>& ambient) const;
  // Every pixel's rays so far, as counts the view's successor can take over (reuse.h): the view is
  // replaced next, and its surfaces move into the history (a view that stays is kept by rows:
  // advance_rebuild)
  void keep_rays();
  // Pixel i's rays so far (its own and those kept from views before), as the history keeps them
  void pixel_counts(size_t i, glm::vec3 position, float& open, float& cast, glm::vec3& origin_sum) const;
  void update_maps(glm::dvec2 gaze_px, bool predicted);  // predicted: the fovea's pixels centre-out
  // What a round planned: the fovea's rays, the periphery's or the rays ahead of the gaze (each of
  // the last two a pass over every pixel)
  enum class Round { fovea, periphery, ahead };
  // A round: the fovea's pixels short of their rays, up to `ray_limit` rays; where it has none, the
  // periphery's, up to `periphery_limit` (0: not this round); where every pixel has its n(E), rays
  // ahead of the gaze, up to `ahead_limit` (0: not this round). `round`: which it planned
  size_t plan_round(uint64_t ray_limit, uint64_t periphery_limit, uint64_t ahead_limit, Round& round);
  // A round of rays ahead of the gaze (plan_round, once every pixel has its n(E))
  size_t plan_ahead(uint64_t ray_limit);
  // Pixel i's next round towards `target` rays: what it lacks, at most doubling its count (kept
  // rays included)
  uint32_t round_rays(size_t i, uint32_t target) const;
  // The fovea's pixels (q = 1, hit, rays) of the current maps at `gaze_px`; centre-out where predicted
  void collect_fovea(glm::dvec2 gaze_px, bool predicted);
  // Room for a round over all n pixels, its pages touched (where a new view needs more)
  void prepare_rounds(size_t n);
  void compose(Image& color);
  // The estimate, where due and where it fits the `left_ms` the frame has before its rays'
  // deadline (else deferred); true where deferred
  bool estimate_unreached(double left_ms);
  // Whether it lowered the size; `in_place`: a still view's, which lower_in_place takes from the
  // view at hand at the next frame (set_scale otherwise: the next frame traces its view at that size)
  bool rescale(double fixed_ms, bool in_place = false);
  void set_scale(double scale);
  // The render size of `scale` (each path to a new size ends here): whether it is held is judged anew
  void take_size(double scale, glm::ivec2 size);
  // A still view's smaller size, taken from the view at hand without tracing: each smaller pixel is
  // one of the larger pixels nearest it, the one with the most rays — its surface point and shading,
  // its eye ray, and its rays so far, kept as the views before's are. (Traced afresh, the smaller
  // view made that frame late by 34–49 ms at 840×525 on two cores.) kept_pixels: the pixels that
  // kept rays. At once, in one frame: where the frames at the larger size are late anyway (their
  // fixed part alone passes the budget) and on the model clock; else taken a few rows at a time
  // while the larger view is still shown (start_rebuild's `lowering`)
  void lower_in_place(uint64_t& kept_pixels);
  // traced_pixels() of a view lowered from the one in use, whose pixel i is its pixel source[i]
  std::shared_ptr<const std::vector<uint32_t>> lowered_pixels(std::vector<uint32_t> source) const;
  // Which larger pixels each smaller pixel of a lowered size stands for: its footprint, those whose
  // nearest smaller pixel it is (one to a few along each axis), and the one nearest its centre
  struct Footprints {
    struct Axis {
      std::vector<uint32_t> first;    // [first[k], first[k + 1]): the larger pixels whose nearest smaller one is k
      std::vector<uint32_t> nearest;  // the larger pixel nearest the centre of smaller pixel k
    };
    Axis columns, rows;
    size_t big_width = 0;
    Footprints() = default;
    Footprints(size_t big_w, size_t big_h, size_t w, size_t h);
    // Smaller pixel (x, y)'s larger pixel: of its footprint, the one with the most rays, else the one
    // nearest its centre
    template <class Rays>
    uint32_t source(size_t x, size_t y, const Rays& rays) const;
  };
  // "rendering at WxH (P %)" and why, where the size is below the one asked for; "" at full size
  std::string size_note(const char* why) const;
  // A camera at rest gets back the size it had before it moved, and a still view made smaller for
  // its fixed part a larger one where that part fits again (`why`: the note then). That view is
  // built a few rows at a time in what frames leave (its surfaces, their shading, its eye rays and
  // maps, the rays it keeps) while the smaller one is still shown, and taken over once complete: the
  // full-size surfaces at once made that frame late by 50–90 ms at 840×525 on two cores. (On the wall
  // clock; the model clock takes the size at once.)
  // `lowering`: a still view's lower size, taken from the view at hand (lower_in_place's rule) rather
  // than traced; `why` is then the whole note
  void start_rebuild(double scale, std::string why, bool lowering = false);
  // A larger size for a still view (a camera come to rest, a fixed part that fits again): built
  // over frames on the wall clock (start_rebuild), at once on the model clock; `why`: the note then.
  void grow_back(double scale, const char* why);
  // Steps of ~1 ms until then (frame's clock), of at most `rows_left` rows in all (counted down);
  // `gaze_px`: where the frame's fovea is (the size asked for's pixels)
  void advance_rebuild(const Timer& frame_timer, double until_ms, int& rows_left, glm::dvec2 gaze_px);
  void adopt_rebuild(uint64_t& kept_pixels);
  glm::dvec2 px_to_deg(glm::dvec2 px) const;
  glm::dvec2 deg_to_px(glm::dvec2 deg) const;

  FrameRenderer& renderer_;
  const Scene& scene_;
  RenderParams requested_, params_;
  LoopSettings settings_;
  std::optional<double> given_margin_ms_;  // the margin the settings gave, before a later budget's half bounded it
  double scale_ = 1;
  glm::ivec2 traced_size_{0};                                   // (traced_size())
  std::shared_ptr<const std::vector<uint32_t>> traced_pixels_;  // (traced_pixels())
  std::optional<double> lower_to_;                              // a still view's lower size, for the next frame to take (lower_in_place)
  std::string note_;
  // The size is held at min_scale, its base shading past 60 % of the budget: why (note() says it in
  // place of note_ until the base shading fits again or the size changes)
  std::optional<std::string> held_note_;
  LandingPredictor predictor_;
  std::optional<glm::dvec2> measured_px_;
  std::optional<double> last_sample_s_;         // the latest valid sample's time
  std::optional<double> last_pushed_s_;         // the latest sample's time taken, valid or not
  uint32_t clock_restarts_ = 0;                 // times the samples' clock went back (push_gaze)
  double clock_back_s_ = 0;                     // … by how much, the latest time
  RecentMedian<16> intervals_s_;                // … and the intervals between the latest valid samples (gaze_note)
  std::optional<glm::dvec2> known_landing_px_;  // set_known_landing
  bool have_view_ = false;
  Camera camera_;
  GBuffer gbuffer_;
  uint64_t gbuffer_version_ = 0;
  std::vector<glm::vec3> lit_, ambient_;  // S and A of the colour S + k_a·A
  FoveationMaps maps_;
  std::vector<float> ray_x_, ray_y_, ray_z_;  // each pixel's unit eye ray (the maps' input that the gaze leaves alone)
  std::optional<glm::dvec2> maps_gaze_;
  std::optional<glm::dvec2> maps_full_gaze_;  // where the maps were last evaluated at every pixel (update_maps)
  glm::ivec4 maps_box_{0};                    // the pixels [x0, x1) × [y0, y1) the latest update evaluated
  bool maps_predicted_ = false;               // the maps are at a predicted landing
  std::vector<uint32_t> cast_, open_;         // rays of this view: pixel i's sequence [0, cast_[i]) under view_seed_
  std::vector<float> kept_cast_, kept_open_;  // rays kept from the views before (reprojected; empty: none)
  std::vector<glm::vec3> kept_origin_;        // Σ of the kept rays' origins (empty: each from the pixel's own surface point)
  AoHistory history_;                         // the view before, at a new view
  AoCounts counts_;                           // scratch: the counts handed to and from the history
  bool forget_ = false;                       // reset(): the next view starts afresh
  uint64_t view_seed_ = 0;                    // the AO seed of this view's rays
  uint32_t views_ = 0;                        // views traced so far
  std::array<Image, 2> spares_;               // shown frames' images handed back (recycle), or made for a view's first frames
  bool fits_view(const Image& image) const;   // an image of the view's size and three channels
  // The visibility of the pixels without rays yet, from those around them (estimate_unreached)
  PullPush pull_push_;
  bool unreached_possible_ = true;  // some pixel may lack the rays its n(E) asks for
  bool estimates_ = false;          // pull_push_ holds estimates for this view
  bool grid_pending_ = false;       // the view's coarse grid is still to be planned (plan_round)
  int estimate_age_ = 0;            // frames since they were made
  uint64_t estimates_made_ = 0;
  uint64_t maps_everywhere_ = 0;
  bool reached_ = true;  // a pixel outside the fovea got its first rays, or the maps changed everywhere, since then
  std::vector<AoRayTask> tasks_;
  std::vector<uint32_t> blocked_;
  std::vector<uint8_t> done_;
  std::vector<uint32_t> order_;          // scratch: pixels by priority bucket
  std::vector<uint32_t> fovea_;          // the fovea's pixels (q = 1, hit, rays) for the current maps
  std::vector<uint32_t> fovea_scratch_;  // scratch: a predicted fovea's centre-out order
  SweepKeys periphery_keys_;             // each pixel's bucket in the periphery's sweep (plan_round)
  SweepKeys ahead_keys_;                 // … in the sweep of the rays ahead of the gaze (plan_ahead)
  bool last_new_view_ = false;           // the previous frame traced a new view
  float ao_distance_ = 0, epsilon_ = 0, tau_fovea_ = 0;
  double rays_per_ms_ = 0;  // wall clock: measured, smoothed
  double finish_ms_ = 1;    // wall clock: composing and the fovea's state at a frame's end, measured
  double slip_ms_ = 0;      // wall clock: how much later than planned frames ended, a decaying maximum
  double plan_ms_ = 0.5;    // wall clock: a round's planning, measured, smoothed
  // Wall clock: what a sweep's planning costs, where it computes buckets over a wide area (after new
  // maps everywhere or in their box: a pass over those pixels) and where only over the pixels
  // traced since the last (the sort alone, about a third of a full sweep at 840×525)
  SweepCost sweep_, narrow_sweep_;
  // What an estimate of the pixels without rays costs (wall clock; a view's first is made at once,
  // so it is timed before it is asked)
  SweepCost estimate_cost_;
  SweepCost& next_sweep() { return (all_converged_ ? ahead_keys_ : periphery_keys_).wide() ? sweep_ : narrow_sweep_; }
  // The last periphery sweep found every pixel converged and the maps have not been recomputed
  // since (every view, size and gaze change recomputes them; no ray is traced while all have
  // converged): the next sweep would find the same, so none is made
  bool all_converged_ = false;
  // Likewise for the rays ahead of the gaze: every pixel has n_max (meaningful while all_converged_,
  // cleared as it is set)
  bool ahead_done_ = false;
  FixedPartWindow fixed_;                // the latest frames' cost besides their rays, since the last rescale
  RecentMedian<kBudgetFrames> budgets_;  // wall clock: the latest frames' budgets
  std::optional<double> motion_scale_;   // the size lowered for a moving camera: the scale before
  int still_frames_ = 0;                 // frames since the camera last moved
  double last_view_cost_ms_ = 0;         // the latest frame's fixed part where it traced a new view (0 where not)
  // What a moved view costs per pixel (wall clock: surfaces, shading, the rays kept), the latest
  // measured; 0 before one. A view without rays to keep (the first) is measured apart: a moved one
  // is estimated from it until one is measured
  double moved_view_ms_per_px_ = 0, fresh_view_ms_per_px_ = 0;
  struct Rebuild {
    double scale = 1;
    std::string why;  // the note's reason once it is shown
    int width = 0, height = 0;
    // A larger size: surfaces, shading, keep, reproject. A lowered one: gather (its pixels' surfaces,
    // shading, eye rays and maps, from their larger pixels), gather_rays (their rays so far, kept).
    // Then both: estimate (the pull of the pixels without rays, by rows), estimate_push (the
    // pyramid's coarser levels and the push), and refresh_maps (the maps evaluated again at the gaze, where it has
    // moved kMapsStaleDeg since they were: else the frame that takes the view over evaluates them
    // everywhere, and with them it took 4.0–4.2 ms where the budget was 4)
    enum Stage { surfaces, shading, keep, reproject, gather, gather_rays, estimate, estimate_push, refresh_maps, done } stage = surfaces;
    bool lowering = false;
    Footprints footprints;         // (lowering)
    std::vector<uint32_t> source;  // (lowering) each pixel's larger pixel, row by row
    // (lowering a view itself lowered) each pixel's pixel of the view traced last (traced_pixels())
    std::vector<uint32_t> traced;
    // The view's first estimate of its pixels without rays (estimate_unreached's), from the rays it
    // keeps, made by rows: made as the view was taken over, with the maps evaluated everywhere, it
    // made that frame late at a budget of 4 ms (4.1–6.6 ms at 840×525 on two cores)
    PullPush pull_push;
    bool unreached = false;  // … some pixel that asks for rays has none
    bool pushed = false;     // … and some pixel has rays: pull_push holds the estimate
    bool estimated = false;  // … made (estimate_push)
    int row = 0;             // the stage's next row
    double rows_per_ms = 0;  // the stage's pace, measured (0: not yet)
    GBuffer gbuffer;         // rows traced so far (memory reserved for the whole view, touched row by row)
    std::vector<glm::vec3> lit, ambient;
    std::vector<float> ray_x, ray_y, ray_z;  // unit eye rays
    FoveationMaps maps;
    glm::dvec2 gaze{0};  // where the maps are
    AoCounts kept;       // the rays the view takes over from the smaller one
    uint64_t kept_pixels = 0;
    // The memory its first two frames are composed into (touched row by row with the shading; the
    // second frame's, made afresh, took 5.4 ms with 1,200 page faults at 820×513 where the budget was 4)
    std::array<Image, 2> images;
  };
  std::optional<Rebuild> rebuild_;
  // A still view lowered (at frame `index`, with that budget): its growing back is held for
  // grow_hold_frames_ where it was lowered again soon after it came back (lowered_still)
  struct LoweredStill {
    int index = 0;
    double budget_ms = 0;
  };
  std::optional<LoweredStill> lowered_still_;
  std::optional<int> grown_index_;  // the frame a still view's size last began to come back
  int grow_hold_frames_ = 0;
  void lowered_still(int index);
  int index_ = 0;
  // Wall clock: the chunks a frame's rays left to threads the machine had paused (AoRayBatch::
  // leave_behind_after_ms), waited for at the next frame's start; and when its rays left them.
  // (Last: destroyed first, before the tasks and surfaces those chunks read)
  std::chrono::steady_clock::time_point left_at_{};
  AoLeftBehind left_behind_;
};

}  // namespace foveal
