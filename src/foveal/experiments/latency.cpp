// foveal/experiments/latency.cpp — three display loops on recorded gaze under a simulated clock.
#include "foveal/experiments/latency.h"

#include "foveal/experiments/stalls_report.h"
#include "foveal/gaze/detect.h"
#include "foveal/gaze/fixation.h"
#include "foveal/io/plot.h"
#include "foveal/util/cpu_share.h"
#include "foveal/util/error.h"
#include "foveal/util/stats.h"
#include "foveal/util/timer.h"
#include "foveal/util/units.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>

namespace foveal {

namespace {

// Each frame's budget: the one given, else a refresh
double frame_budget(const LatencyParams& p) { return p.budget_ms.value_or(1000.0 / p.refresh_hz); }

constexpr size_t kWatchedThreads = 8;  // other processes' threads read around each wall-clock frame

// The q = 1 pixels (that hit the scene) around a landing, and the reference's noise over them.
struct FoveaMask {
  std::vector<uint32_t> pixels;
  double noise_mse = 0, noise_rel_se = 0;
};

// Pixel i of `a` against pixel j of `b` (the same pixel where j is not given): mean squared error
// over the channels.
double pixel_squared_error(const Image& a, const Image& b, size_t i, std::optional<size_t> j = std::nullopt) {
  const size_t bi = j.value_or(i);
  double sq = 0;
  for (size_t c = 0; c < 3; ++c) {
    const double d = static_cast<double>(a.pixels[i * 3 + c]) - b.pixels[bi * 3 + c];
    sq += d * d;
  }
  return sq / 3;
}

// Mean and ½·sd/(mean·√n), the RMSE's relative standard error (as quality/compare.cpp).
std::pair<double, double> mse_and_rel_se(const std::vector<double>& e) {
  if (e.empty()) return {0, 0};
  double sum = 0, sq = 0;
  for (double v : e) sum += v, sq += v * v;
  const double n = static_cast<double>(e.size()), mse = sum / n;
  const double var = std::max(0.0, sq / n - mse * mse);
  return {mse, mse > 0 ? 0.5 * std::sqrt(var / n) / mse : 0.0};
}

FoveaMask fovea_mask(const RenderParams& params, const GBuffer& g, glm::dvec2 landing, const Image& ref, const Image& ref2) {
  FoveaMask m;
  const FoveationMaps maps = foveation_maps(params, landing);
  std::vector<double> noise;
  for (size_t i = 0; i < maps.quality.size(); ++i)
    if (maps.quality[i] >= 1.0f && g.hit(i)) {
      m.pixels.push_back(static_cast<uint32_t>(i));
      noise.push_back(pixel_squared_error(ref2, ref, i));
    }
  std::tie(m.noise_mse, m.noise_rel_se) = mse_and_rel_se(noise);
  return m;
}

// The fovea's RMSE as a multiple of the reference's noise over the same pixels (squared errors
// `e`; the noise's mean and relative standard error), and whether it is within it (ratio ≤ 1 + 2
// standard errors).
std::pair<double, bool> within_noise(const std::vector<double>& e, double noise_mse, double noise_rel_se) {
  if (e.empty() || !(noise_mse > 0)) return {NAN, false};
  const auto [mse, rel_se] = mse_and_rel_se(e);
  const double ratio = std::sqrt(mse / noise_mse);
  const double se = ratio * std::hypot(rel_se, noise_rel_se);
  return {ratio, ratio <= 1.0 + 2.0 * se};
}

// … of a frame at the references' size, over the mask's pixels.
std::pair<double, bool> fovea_error(const FoveaMask& m, const Image& image, const Image& ref) {
  if (image.width != ref.width || image.height != ref.height) return {NAN, false};
  std::vector<double> e;
  e.reserve(m.pixels.size());
  for (uint32_t i : m.pixels) e.push_back(pixel_squared_error(image, ref, i));
  return within_noise(e, m.noise_mse, m.noise_rel_se);
}

// A view at a lowered size whose pixel j shows the surface of pixel (*pixels)[j] of the view traced
// last (RealtimeLoop::traced_pixels), and, per fovea mask, the pairs (j, that pixel) within it:
// made once a view (each frame's search of every pixel had taken tens of milliseconds).
struct LoweredView {
  std::shared_ptr<const std::vector<uint32_t>> pixels;
  std::vector<int32_t> inverse;  // the references' pixel i: the view's pixel showing it, or -1
  std::vector<std::optional<std::vector<std::pair<uint32_t, uint32_t>>>> fovea;  // per mask
  void show(std::shared_ptr<const std::vector<uint32_t>> next, size_t full_pixels, size_t masks) {
    if (next == pixels) return;
    pixels = std::move(next);
    inverse.assign(pixels ? full_pixels : 0, -1);
    if (pixels)
      for (size_t j = 0; j < pixels->size(); ++j)
        if ((*pixels)[j] < inverse.size()) inverse[(*pixels)[j]] = static_cast<int32_t>(j);
    fovea.assign(masks, std::nullopt);
  }
  const std::vector<std::pair<uint32_t, uint32_t>>& of(const FoveaMask& m, size_t k) {
    if (!fovea[k]) {
      fovea[k].emplace();
      for (uint32_t i : m.pixels)
        if (i < inverse.size() && inverse[i] >= 0) fovea[k]->emplace_back(static_cast<uint32_t>(inverse[i]), i);
    }
    return *fovea[k];
  }
};

// The same for a frame at a lowered size: over the fovea's pixels it shows (`pairs`: its pixel j
// showing the references' pixel i), each against the references at the pixel it shows, the noise
// over the same pixels.
std::pair<double, bool> lowered_fovea_error(const std::vector<std::pair<uint32_t, uint32_t>>& pairs, const Image& image, const Image& ref,
                                            const Image& ref2) {
  std::vector<double> e, noise;
  e.reserve(pairs.size());
  noise.reserve(pairs.size());
  for (const auto& [j, i] : pairs) {
    e.push_back(pixel_squared_error(image, ref, j, i));
    noise.push_back(pixel_squared_error(ref2, ref, i));
  }
  const auto [noise_mse, noise_rel_se] = mse_and_rel_se(noise);
  return within_noise(e, noise_mse, noise_rel_se);
}

// Angle between two render positions as seen on the display, degrees.
double render_angle_deg(const RenderParams& p, glm::dvec2 a, glm::dvec2 b) {
  auto dir = [&](glm::dvec2 px) {
    return glm::normalize(
        glm::dvec3((px.x / p.width - 0.5) * p.display.width_cm, (px.y / p.height - 0.5) * p.display.height_cm, p.display.distance_cm));
  };
  return angle_between_deg(dir(a), dir(b));
}

// References traced at one size (n_max rays everywhere, two seeds other than the loops'): the size
// asked for's, or that of a view a deadline loop traced smaller (a size growing back).
struct References {
  Image ref, ref2;
  GBuffer g;
};

References trace_references(const LatencyRun& run, const LatencyParams& p, glm::ivec2 size) {
  RenderParams full = p.render;
  full.width = size.x;
  full.height = size.y;
  full.mode = RenderMode::full;
  full.gaze_px.reset();
  FrameOptions apart;
  apart.outputs = {false, false, true};
  apart.use_history = false;
  References r;
  full.seed = p.render.seed + 1000;
  Frame first = run.renderer->render(run.camera, full, apart);
  r.ref = std::move(first.color);
  r.g = std::move(first.gbuffer);
  full.seed = p.render.seed + 2000;
  apart.outputs = FrameOutputs::colour_only();
  r.ref2 = run.renderer->render(run.camera, full, apart).color;
  return r;
}

// What the three loops share: the segment's samples, the saccades, the references and masks.
struct Segment {
  std::vector<double> t;                      // seconds from the recording's first sample
  std::vector<std::optional<glm::dvec2>> px;  // render pixels
  double begin = 0, end = 0, latency_s = 0;
  bool cut = false;  // the segment asked for ran past the recording's last sample: it ends there
  std::vector<LatencySaccade> saccades;
  std::vector<FoveaMask> masks;  // at the size asked for
  Image ref, ref2;
  std::optional<size_t> drawn;  // the timeline picture's saccade
  // Sizes a deadline loop traced its view at, smaller: the references there (traced on first use,
  // kept for every segment), and the masks of this segment's saccades at them
  RenderParams render;
  std::function<const References&(glm::ivec2)> references_at;
  mutable std::map<std::pair<int, int>, std::vector<FoveaMask>> masks_at;
};

// The references a frame is judged against, by the size of the view it comes from, with the masks.
struct Judged {
  const Image& ref;
  const Image& ref2;
  const std::vector<FoveaMask>& masks;
};

Judged judged_at(const Segment& s, glm::ivec2 size) {
  if (size == glm::ivec2(s.ref.width, s.ref.height) || !s.references_at) return {s.ref, s.ref2, s.masks};
  const References& r = s.references_at(size);
  auto [at, fresh] = s.masks_at.try_emplace({size.x, size.y});
  if (fresh) {
    RenderParams params = s.render;
    params.width = size.x;
    params.height = size.y;
    const glm::dvec2 ratio(static_cast<double>(size.x) / s.ref.width, static_cast<double>(size.y) / s.ref.height);
    for (const LatencySaccade& sac : s.saccades) at->second.push_back(fovea_mask(params, r.g, sac.landing_px * ratio, r.ref, r.ref2));
  }
  return {r.ref, r.ref2, at->second};
}

// Which saccade's fovea a frame shown at `t` is judged against: the latest landed one (or, before
// any, the first).
size_t followed_saccade(const Segment& s, double t) {
  size_t k = 0;
  for (size_t j = 0; j < s.saccades.size(); ++j)
    if (s.saccades[j].landing_s <= t) k = j;
  return k;
}

// Judge a shown frame, on screen from `shown_s` until the next frame's refresh `until_s`: every
// saccade that lands before `until_s` and whose fovea has not converged yet is judged on it. The
// frame on screen when the eye lands counts too: one made ready before the landing (at the
// predicted landing) shows a converged fovea 0 ms after it. Also the timeline's error. `judged`:
// the references at the size of the view the frame comes from; a frame lowered from that view
// (`lowered`: its pixels there) is judged on the pixels it shows.
void judge_frame(const Segment& s, const Judged& judged, const Image& image, LoweredView* lowered, double shown_s, double until_s,
                 LatencyLoop& loop, LatencyFrame& frame) {
  const auto error = [&](size_t k) {
    return lowered ? lowered_fovea_error(lowered->of(judged.masks[k], k), image, judged.ref, judged.ref2)
                   : fovea_error(judged.masks[k], image, judged.ref);
  };
  for (size_t j = 0; j < s.saccades.size(); ++j) {
    LatencySaccade& sac = loop.saccades[j];
    if (sac.converged_ms || sac.landing_s >= until_s) continue;
    if (error(j).second) sac.converged_ms = std::max(0.0, shown_s - sac.landing_s) * 1000;
  }
  if (!s.saccades.empty()) frame.fovea_error = error(followed_saccade(s, shown_s)).first;
  if (s.drawn) frame.drawn_error = error(*s.drawn).first;
}

// The display: the frame on screen, judged once the next frame's refresh is known.
struct Screen {
  Image image;
  double shown_s = 0;
  size_t frame = 0;      // its index in the loop's timeline
  glm::ivec2 traced{0};  // the size of the view it comes from, the one traced last (RealtimeLoop::traced_size)
  LoweredView lowered;   // where it was lowered from that view: its pixels there
  bool any = false;
  // A new frame shown at `shown_s`: the one it replaces is judged over the time it was on screen,
  // and returned (for the loop to compose into again)
  Image show(const Segment& s, LatencyLoop& loop, Image next, double next_shown_s, glm::ivec2 next_traced,
             std::shared_ptr<const std::vector<uint32_t>> next_pixels = nullptr) {
    finish(s, loop, next_shown_s);
    Image old = std::move(image);
    image = std::move(next);
    shown_s = next_shown_s;
    frame = loop.timeline.size() - 1;
    traced = next_traced;
    if (next_pixels && next_pixels->size() * 3 != image.pixels.size()) next_pixels.reset();  // (not this image's)
    lowered.show(std::move(next_pixels), static_cast<size_t>(traced.x) * static_cast<size_t>(traced.y), s.saccades.size());
    any = true;
    return old;
  }
  void finish(const Segment& s, LatencyLoop& loop, double until_s) {
    if (!any) return;
    any = false;
    if (image.width != s.ref.width || image.height != s.ref.height) ++loop.frames_lowered;
    if (lowered.pixels || (image.width == traced.x && image.height == traced.y)) {
      judge_frame(s, judged_at(s, traced), image, lowered.pixels ? &lowered : nullptr, shown_s, until_s, loop, loop.timeline[frame]);
      return;
    }
    // (counted, for the report to say which landings' times it may have lengthened)
    ++loop.frames_not_judged;
    for (LatencySaccade& sac : loop.saccades) sac.frames_not_judged += !sac.converged_ms && sac.landing_s < until_s ? 1 : 0;
  }
};

// The clock: a frame of `cost_ms` started at `start` is shown at the first refresh after it is done.
double shown_at(double start, double cost_ms, double period_s, int& missed) {
  const int refreshes = std::max(1, static_cast<int>(std::ceil(cost_ms / 1000 / period_s - 1e-9)));
  missed += refreshes - 1;
  return start + refreshes * period_s;
}

void finish_loop(LatencyLoop& loop, const std::vector<double>& frame_ms) {
  loop.frames = static_cast<int>(frame_ms.size());
  loop.frame_ms_p50 = quantile(frame_ms, 0.5);
  loop.frame_ms_p99 = quantile(frame_ms, 0.99);
}

LatencyLoop run_whole_frame(const LatencyRun& run, const Segment& s, const LatencyParams& p, double budget_ms, double model_rate,
                            double model_fixed) {
  LatencyLoop loop;
  loop.name = "whole-frame";
  loop.budget_ms = budget_ms;
  loop.saccades = s.saccades;
  const double period = 1.0 / p.refresh_hz;
  std::vector<double> frame_ms;
  Screen screen;
  size_t next = 0;
  std::optional<glm::dvec2> gaze;
  for (double t = s.begin; t < s.end;) {
    for (; next < s.t.size() && s.t[next] + s.latency_s <= t; ++next)
      if (s.px[next]) gaze = s.px[next];
    RenderParams params = p.render;
    params.gaze_px = gaze;
    FrameOptions options;
    options.outputs = FrameOutputs::colour_only();
    options.use_history = false;
    const Timer timer;
    Frame f = run.renderer->render(run.camera, params, options);
    const double ms = timer.ms();
    const double cost = p.clock == LoopClock::model ? model_fixed + static_cast<double>(f.stats.ao_rays) / model_rate : ms;
    frame_ms.push_back(cost);
    loop.frames_late += cost > budget_ms ? 1 : 0;
    LatencyFrame lf;
    lf.start_s = t;
    lf.cost_ms = cost;
    lf.shown_s = shown_at(t, cost, period, loop.refreshes_missed);
    lf.gaze_px = f.gaze_px;
    loop.timeline.push_back(lf);
    screen.show(s, loop, std::move(f.color), lf.shown_s, glm::ivec2(p.render.width, p.render.height));
    t = lf.shown_s;
  }
  screen.finish(s, loop, INFINITY);
  finish_loop(loop, frame_ms);
  return loop;
}

// `name`: deadline, deadline+prediction or deadline+oracle
LatencyLoop run_deadline(const LatencyRun& run, const Segment& s, const LatencyParams& p, double budget_ms, const std::string& name,
                         double model_rate, double model_fixed, const std::vector<WatchedThread>& watch) {
  LatencyLoop loop;
  loop.name = name;
  const bool oracle = name == "deadline+oracle", predict = oracle || name == "deadline+prediction";
  loop.budget_ms = budget_ms;
  loop.saccades = s.saccades;
  LoopSettings settings;
  settings.budget_ms = budget_ms;
  settings.predict = predict;
  settings.landing = p.landing;
  settings.clock = p.clock;
  settings.model_rays_per_ms = model_rate;
  settings.model_fixed_ms = model_fixed;
  settings.margin_ms = p.margin_ms;
  settings.periphery_share = p.periphery_share;
  settings.rays_ahead = p.rays_ahead;
  settings.min_scale = p.min_scale;
  RealtimeLoop rt(*run.renderer, *run.scene, p.render, settings);
  // Samples from a second before the segment: the predictor and the fovea start where the eye is
  size_t next = 0;
  while (next < s.t.size() && s.t[next] + s.latency_s <= s.begin - 1.0) ++next;
  for (; next < s.t.size() && s.t[next] + s.latency_s <= s.begin; ++next) rt.push_gaze(s.t[next], s.px[next]);
  rt.recycle(rt.frame(run.camera).color);  // the view's surfaces, before the segment starts (as before a trial)
  const double period = 1.0 / p.refresh_hz;
  std::vector<double> frame_ms;
  std::vector<std::pair<double, glm::dvec2>> predictions;  // frame start, predicted landing
  Screen screen;
  std::vector<LatencyFramePart> parts;
  double left_frame_ms = NAN;  // the latest frame's time where its rays left chunks behind
  for (double t = s.begin; t < s.end;) {
    for (; next < s.t.size() && s.t[next] + s.latency_s <= t; ++next) rt.push_gaze(s.t[next], s.px[next]);
    if (oracle) {  // a flight the predictor has detected goes to its saccade's true landing (one of at least --min-amplitude)
      std::optional<glm::dvec2> known;
      const LandingState& flight = rt.predictor().state();
      if (flight.in_flight)
        for (const LatencySaccade& sac : s.saccades)
          if (flight.onset_s >= sac.landing_s - sac.duration_ms / 1000 - 0.02 && flight.onset_s < sac.landing_s) known = sac.landing_px;
      rt.set_known_landing(known);
    }
    // Wall clock: the threads' times and the page faults around the frame (read outside its timing)
    const bool wall = p.clock == LoopClock::wall;
    const Timer window;
    const ThreadTimes threads_before = wall ? read_thread_times() : ThreadTimes{};
    const ThreadTimes others_before = wall ? read_watched(watch) : ThreadTimes{};
    const double faults_before = wall ? page_faults() : NAN;
    if (p.before_frame) p.before_frame(rt, static_cast<int>(frame_ms.size()));
    LoopFrame f = rt.frame(run.camera);
    frame_ms.push_back(f.cost_ms);
    loop.frames_late += f.late ? 1 : 0;
    if (std::isfinite(left_frame_ms) && std::isfinite(f.left_behind_ms)) {  // had the frame before waited for them
      const bool late = left_frame_ms + f.left_behind_ms > budget_ms;
      loop.late_had_they_waited += late ? 1 : 0;
      if (late) loop.most_saved_ms = std::max(loop.most_saved_ms, f.left_behind_ms);
    }
    left_frame_ms = f.chunks_left_behind > 0 ? f.ms : NAN;
    loop.frames_left_behind += f.chunks_left_behind > 0 ? 1 : 0;
    if (wall) {
      const double faults_after = page_faults();
      const ThreadTimes threads_after = read_thread_times();
      const ThreadTimes others_after = read_watched(watch);
      const double window_ms = window.ms();
      const auto [other, other_ms] = busiest_watched(watch, others_before, others_after);
      parts.push_back({static_cast<int>(parts.size()), t, f.ms, f.maps_ms, f.plan_ms, f.trace_ms, f.compose_ms,
                       std::max(0.0, f.rays_end_ms - f.deadline_ms), std::max(0.0, (f.ms - f.rays_end_ms) - f.compose_planned_ms), "",
                       longest_wait_ms(threads_before, threads_after),
                       cpu_ms(threads_before, threads_after, current_thread_id()) / window_ms, faults_after - faults_before, other,
                       watch.empty() ? NAN : other_ms});
    }
    LatencyFrame lf;
    lf.start_s = t;
    lf.cost_ms = f.cost_ms;
    lf.shown_s = shown_at(t, f.cost_ms, period, loop.refreshes_missed);
    lf.gaze_px = f.gaze_px / f.scale;
    lf.predicted = f.predicted;
    lf.rays = f.rays;
    lf.scale = f.scale;  // (rt.scale() may be the next frame's, a lower size decided)
    lf.fovea_converged = f.fovea_converged;
    lf.sweeps = f.sweeps;
    if (wall) {
      lf.maps_ms = f.maps_ms;
      lf.plan_ms = f.plan_ms;
      lf.trace_ms = f.trace_ms;
      lf.compose_ms = f.compose_ms;
    }
    if (f.predicted) predictions.emplace_back(t, lf.gaze_px);
    loop.timeline.push_back(lf);
    rt.recycle(screen.show(s, loop, std::move(f.color), lf.shown_s, rt.traced_size(), rt.traced_pixels()));
    t = lf.shown_s;
  }
  screen.finish(s, loop, INFINITY);
  loop.late = late_frame_parts(parts, budget_ms);
  loop.scale = rt.scale();
  for (LatencySaccade& sac : loop.saccades)  // the last prediction made before the landing
    for (const auto& [start, at] : predictions)
      if (start < sac.landing_s && start > sac.landing_s - sac.duration_ms / 1000 - 0.05)
        sac.predicted_error_deg = render_angle_deg(p.render, at, sac.landing_px);
  finish_loop(loop, frame_ms);
  return loop;
}

// The segment's samples in render pixels, and its saccades (nhr, the recommended detector) landing inside it.
Segment make_segment(const Recording& rec, const LatencyParams& p) {
  Segment s;
  if (rec.samples.empty()) fail("recording {}: no samples", rec.source);
  const double t0 = rec.samples.front().t_s;
  s.begin = p.start_s;
  if (s.begin >= rec.duration_s()) fail("start_s: {} s is past the end of {} ({:.1f} s)", p.start_s, rec.source, rec.duration_s());
  // A segment past the recording's last sample ends there: the frames after it would show a gaze
  // held where the recording left it, counted as if the eye had stayed
  s.end = std::min(p.start_s + p.duration_s, rec.duration_s());
  s.cut = p.start_s + p.duration_s > rec.duration_s();
  const double rate = rec.rate_hz();
  s.latency_s = p.tracker_latency_ms ? *p.tracker_latency_ms / 1000 : (rate > 0 ? 1.0 / rate : 0.0) + 0.002;
  const glm::dvec2 scale(static_cast<double>(p.render.width) / rec.screen_px.x, static_cast<double>(p.render.height) / rec.screen_px.y);
  for (const GazeSample& g : rec.samples) {
    s.t.push_back(g.t_s - t0);
    s.px.push_back(g.valid ? std::optional<glm::dvec2>(g.px * scale) : std::nullopt);
  }
  const GazeGeometry geometry(p.render.display, rec.screen_px);
  const EventDetection events = detect_events(rec, geometry, kRecommendedEventMethod, EventParams{}, FixationParams{});
  for (size_t k = 0; k < events.events.size(); ++k) {
    const DetectedEvent& e = events.events[k];
    if (e.label != EventLabel::saccade || !(e.amplitude_deg >= p.min_amplitude_deg)) continue;
    const GazeSample& last = rec.samples[e.last];
    const double landing = last.t_s - t0;
    if (landing < s.begin || landing >= s.end || !last.valid) continue;
    // Where the eye came to rest: the median of the samples of the 150 ms after the saccade (up to
    // the next event that moves it), past its post-saccadic oscillation
    std::vector<double> xs, ys;
    for (size_t i = e.last + 1; i < rec.samples.size() && rec.samples[i].t_s <= last.t_s + 0.150; ++i) {
      const EventLabel l = events.labels[i];
      if (l == EventLabel::saccade || l == EventLabel::blink) break;
      if (l == EventLabel::pso || !rec.samples[i].valid) continue;
      xs.push_back(rec.samples[i].px.x);
      ys.push_back(rec.samples[i].px.y);
    }
    const glm::dvec2 rest = xs.empty() ? last.px : glm::dvec2(quantile(xs, 0.5), quantile(ys, 0.5));
    const glm::dvec2 px = rest * scale;
    if (px.x < 0 || px.y < 0 || px.x >= p.render.width || px.y >= p.render.height) continue;
    LatencySaccade sac;
    // How long the eye stayed: until its next saccade (of any size) or blink
    sac.fixation_ms = (rec.samples.back().t_s - last.t_s) * 1000;
    for (size_t m = k + 1; m < events.events.size(); ++m)
      if (events.events[m].label == EventLabel::saccade || events.events[m].label == EventLabel::blink) {
        sac.fixation_ms = (rec.samples[events.events[m].first].t_s - last.t_s) * 1000;
        break;
      }
    sac.amplitude_deg = e.amplitude_deg;
    sac.duration_ms = e.duration_s * 1000;
    sac.landing_s = landing;
    sac.landing_px = px;
    s.saccades.push_back(sac);
  }
  return s;
}

// "composing 2, tracing 1": the late frames' parts, most frequent first
std::string late_summary(const std::vector<LatencyFramePart>& late) {
  std::vector<std::pair<std::string, int>> counts;
  for (const LatencyFramePart& f : late) {
    auto it = std::find_if(counts.begin(), counts.end(), [&](const auto& c) { return c.first == f.part; });
    if (it == counts.end())
      counts.emplace_back(f.part, 1);
    else
      ++it->second;
  }
  std::stable_sort(counts.begin(), counts.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string out;
  for (const auto& [part, n] : counts) out += fmt::format("{}{} {}", out.empty() ? "" : ", ", part, n);
  return out;
}

nlohmann::json number_or_null(double v) { return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v); }

std::string ms_or_dash(std::optional<double> v) { return v ? fmt::format("{:.0f}", *v) : "—"; }
std::string ms_or_dash(double v) { return std::isfinite(v) ? fmt::format("{:.0f}", v) : "—"; }

// What a segment cut at the recording's end says, after its times ("" where it was not cut).
std::string cut_note(bool cut, const LatencyParams& p) {
  return cut ? fmt::format(", where the recording ends ({:g} s asked for from {:g} s)", p.duration_s, p.start_s) : std::string();
}

nlohmann::json loop_json(const LatencyLoop& l) {
  nlohmann::json j;
  j["budget_ms"] = l.budget_ms;
  j["frames"] = l.frames;
  j["frames_late"] = l.frames_late;
  j["refreshes_missed"] = l.refreshes_missed;
  j["frame_ms_p50"] = l.frame_ms_p50;
  j["frame_ms_p99"] = l.frame_ms_p99;
  j["resolution_scale"] = l.scale;
  j["frames_lowered"] = l.frames_lowered;
  j["frames_not_judged"] = l.frames_not_judged;
  j["saccades"] = nlohmann::json::array();
  for (const LatencySaccade& s : l.saccades) {
    nlohmann::json js;
    js["amplitude_deg"] = s.amplitude_deg;
    js["duration_ms"] = s.duration_ms;
    js["landing_s"] = s.landing_s;
    js["landing_px"] = {s.landing_px.x, s.landing_px.y};
    js["landing_to_converged_ms"] = s.converged_ms ? nlohmann::json(*s.converged_ms) : nlohmann::json(nullptr);
    js["ray_bound_ms"] = s.ray_bound_ms;
    if (std::isfinite(s.model_ray_bound_ms)) js["model_ray_bound_ms"] = s.model_ray_bound_ms;
    js["fixation_ms"] = s.fixation_ms;
    if (s.predicted_error_deg) js["predicted_error_deg"] = *s.predicted_error_deg;
    js["frames_not_judged"] = s.frames_not_judged;
    j["saccades"].push_back(js);
  }
  j["timeline"] = nlohmann::json::array();
  for (const LatencyFrame& f : l.timeline)
    j["timeline"].push_back({{"start_s", f.start_s},
                             {"shown_s", f.shown_s},
                             {"cost_ms", f.cost_ms},
                             {"fovea_px", {f.gaze_px.x, f.gaze_px.y}},
                             {"predicted", f.predicted},
                             {"rays", f.rays},
                             {"scale", f.scale},
                             {"fovea_converged", number_or_null(f.fovea_converged)},
                             {"maps_ms", number_or_null(f.maps_ms)},
                             {"plan_ms", number_or_null(f.plan_ms)},
                             {"sweeps", f.sweeps},
                             {"trace_ms", number_or_null(f.trace_ms)},
                             {"compose_ms", number_or_null(f.compose_ms)},
                             {"fovea_error", number_or_null(f.fovea_error)}});
  const auto median = l.median_converged_ms();
  j["median_landing_to_converged_ms"] = median ? nlohmann::json(*median) : nlohmann::json(nullptr);
  if (l.name != "whole-frame") {
    j["frames_left_behind"] = l.frames_left_behind;
    j["late_had_they_waited"] = l.late_had_they_waited;
    j["late_frames"] = nlohmann::json::array();
    for (const LatencyFramePart& f : l.late)
      j["late_frames"].push_back({{"index", f.index},
                                  {"start_s", f.start_s},
                                  {"ms", f.ms},
                                  {"part", f.part},
                                  {"maps_ms", f.maps_ms},
                                  {"plan_ms", f.plan_ms},
                                  {"trace_ms", f.trace_ms},
                                  {"compose_ms", f.compose_ms},
                                  {"rays_over_ms", f.rays_over_ms},
                                  {"compose_over_ms", f.compose_over_ms},
                                  {"cpu_wait_ms", number_or_null(f.cpu_wait_ms)},
                                  {"cpu_share", number_or_null(f.cpu_share)},
                                  {"page_faults", number_or_null(f.faults)},
                                  {"other_process", f.other},
                                  {"other_ms", number_or_null(f.other_ms)}});
  }
  return j;
}

}  // namespace

std::vector<LatencyFramePart> late_frame_parts(const std::vector<LatencyFramePart>& frames, double budget_ms) {
  // What the maps and planning usually take where they run (most frames reuse the maps)
  std::vector<double> maps, plan;
  for (const LatencyFramePart& f : frames) {
    if (f.maps_ms > 0) maps.push_back(f.maps_ms);
    if (f.plan_ms > 0) plan.push_back(f.plan_ms);
  }
  const double maps_usual = median(maps), plan_usual = median(plan);
  std::vector<LatencyFramePart> late;
  for (LatencyFramePart f : frames) {
    if (!(f.ms > budget_ms)) continue;
    // Composing ran over its plan by more than the rays over their deadline; else the maps or a
    // planning pass, where one took at least half the overrun longer than usual; else tracing (a
    // thread paused inside a batch of rays, which stops only between chunks)
    const double maps_over = f.maps_ms - maps_usual, plan_over = f.plan_ms - plan_usual;
    if (f.compose_over_ms >= f.rays_over_ms)
      f.part = "composing";
    else if (std::max(maps_over, plan_over) >= 0.5 * f.rays_over_ms)
      f.part = maps_over >= plan_over ? "maps" : "planning";
    else
      f.part = "tracing";
    late.push_back(f);
  }
  return late;
}

std::string late_threads_summary(const std::vector<LatencyFramePart>& late, double budget_ms) {
  double wait = 0, faults_lo = INFINITY, faults_hi = 0, share_lo = INFINITY, share_hi = 0;
  int known = 0, explained = 0;
  for (const LatencyFramePart& f : late) {
    if (std::isnan(f.cpu_wait_ms) || std::isnan(f.cpu_share) || std::isnan(f.faults)) continue;
    ++known;
    wait = std::max(wait, f.cpu_wait_ms);
    explained += f.ms - f.cpu_wait_ms <= budget_ms ? 1 : 0;
    faults_lo = std::min(faults_lo, f.faults);
    faults_hi = std::max(faults_hi, f.faults);
    share_lo = std::min(share_lo, f.cpu_share);
    share_hi = std::max(share_hi, f.cpu_share);
  }
  if (!known) return "";
  const auto range = [](double lo, double hi, const char* spec) {  // "0.9–1.0", or "1.0" where both read so
    const std::string a = fmt::format(fmt::runtime(spec), lo), b = fmt::format(fmt::runtime(spec), hi);
    return a == b ? a : a + "–" + b;
  };
  std::string others;  // the busiest watched process of each late frame
  int listed = 0;
  for (const LatencyFramePart& f : late) {
    if (std::isnan(f.other_ms)) continue;
    if (++listed > 8) {
      others += ", …";
      break;
    }
    others += (others.empty() ? "" : ", ") + (f.other.empty() ? std::string("none") : fmt::format("{} {:.1f} ms", f.other, f.other_ms));
  }
  return fmt::format("run delay ≤ {:.1f} ms ({} of {} on time without it), page faults {}, the calling thread on a CPU {} of the time{}",
                     wait, explained, known, range(faults_lo, faults_hi, "{:.0f}"), range(share_lo, share_hi, "{:.1f}"),
                     others.empty() ? "" : "; the other process busiest in each: " + others);
}

std::optional<double> LatencyLoop::median_converged_ms() const {
  // Saccades never converged within the segment count as the longest (they took at least that)
  std::vector<double> v;
  bool any = false;
  for (const LatencySaccade& s : saccades) {
    v.push_back(s.converged_ms.value_or(INFINITY));
    any = any || s.converged_ms.has_value();
  }
  if (!any) return std::nullopt;
  const double m = quantile(v, 0.5);
  return std::isfinite(m) ? std::optional<double>(m) : std::nullopt;
}

void validate(const LatencyParams& p) {
  validate(p.render);
  if (p.render.mode != RenderMode::foveated) fail("mode: bench latency renders foveated frames");
  validate(p.landing);
  // With no AO rays every fovea would be 'converged' at once: no figure would mean anything
  if (p.render.foveation.max_rays < 1)
    fail("max_rays: bench latency judges the fovea's AO; must be >= 1, got {}", p.render.foveation.max_rays);
  if (!(p.refresh_hz >= 1 && p.refresh_hz <= 1000)) fail("refresh_hz: must be in [1, 1000] Hz, got {}", p.refresh_hz);
  if (p.budget_ms && !(*p.budget_ms > 0 && *p.budget_ms <= 10000)) fail("frame_budget_ms: must be in (0, 10000] ms, got {}", *p.budget_ms);
  if (p.tracker_latency_ms && !(*p.tracker_latency_ms >= 0 && *p.tracker_latency_ms < 1000))
    fail("latency_ms: must be in [0, 1000) ms, got {}", *p.tracker_latency_ms);  // (the tracker's: --latency-ms, latency_ms=)
  if (!(p.start_s >= 0) || !std::isfinite(p.start_s)) fail("start_s: must be >= 0 s, got {}", p.start_s);
  if (!(p.duration_s > 0) || p.duration_s > 3600) fail("duration_s: must be in (0, 3600] s, got {}", p.duration_s);
  if (!(p.min_amplitude_deg >= 0)) fail("min_amplitude_deg: must be >= 0, got {}", p.min_amplitude_deg);
  if (p.model_rays_per_ms && !(*p.model_rays_per_ms > 0 && std::isfinite(*p.model_rays_per_ms)))
    fail("model_rays_per_ms: must be > 0, got {}", *p.model_rays_per_ms);
  if (p.model_fixed_ms && !(*p.model_fixed_ms >= 0 && std::isfinite(*p.model_fixed_ms)))
    fail("model_fixed_ms: must be >= 0, got {}", *p.model_fixed_ms);
  if ((p.model_rays_per_ms || p.model_fixed_ms) && p.clock != LoopClock::model) fail("model_rays_per_ms: needs the model clock");
  if (p.model_rays_per_ms.has_value() != p.model_fixed_ms.has_value())
    fail("model_fixed_ms: give both parts of the cost model, or neither");
  {  // the loop's own rules, checked before the references are traced
    LoopSettings loop;
    loop.budget_ms = frame_budget(p);
    loop.margin_ms = p.margin_ms;
    loop.periphery_share = p.periphery_share;
    loop.min_scale = p.min_scale;
    validate(loop);
  }
  if (p.loops.empty()) fail("loops: give at least one (whole-frame, deadline, deadline+prediction, deadline+oracle)");
  for (const std::string& l : p.loops)
    if (l != "whole-frame" && l != "deadline" && l != "deadline+prediction" && l != "deadline+oracle")
      fail("loops: unknown loop '{}' (known: whole-frame, deadline, deadline+prediction, deadline+oracle)", l);
  for (size_t k = 0; k < p.loops.size(); ++k)  // (the report keys each loop's figures by its name)
    if (std::find(p.loops.begin() + static_cast<std::ptrdiff_t>(k) + 1, p.loops.end(), p.loops[k]) != p.loops.end())
      fail("loops: '{}' given twice", p.loops[k]);
}

LatencyReport run_latency_bench(const LatencyRun& run, const std::vector<Recording>& recordings, const LatencyParams& p) {
  validate(p);
  if (!run.renderer || !run.scene) fail("run_latency_bench: no renderer or scene");
  for (const Recording& rec : recordings) {  // before the references are traced
    if (rec.samples.size() < 2 || !(rec.duration_s() > 0))
      fail("{}: {} sample{} at one time: bench latency replays a recording over time", rec.source, rec.samples.size(),
           rec.samples.size() == 1 ? "" : "s");
    const double hz = rec.rate_hz();  // (0 where no two samples follow each other in time)
    if (const std::string unseen = hz > 0 ? unseen_saccades_note(1 / hz, "bench latency") : ""; !unseen.empty())
      fail("{}: its samples come {:.3g} s apart: {}", rec.source, 1 / hz, unseen);
    if (p.start_s >= rec.duration_s()) fail("start_s: {} s is past the end of {} ({:.1f} s)", p.start_s, rec.source, rec.duration_s());
  }
  const auto say = [&](const std::string& line) {
    if (run.say) run.say(line);
  };
  const double budget = frame_budget(p);
  LatencyReport report;
  // The machine's threads now: what else runs while the references are traced is watched around
  // each wall-clock frame (the likely takers of a late frame's cores), and what ran during the
  // whole run is named at its end
  const bool wall = p.clock == LoopClock::wall;
  const MachineThreads census = read_machine_threads();
  // The view: references (n_max everywhere, two seeds other than the loops'), surfaces, the raw rate
  RenderParams full = p.render;
  full.mode = RenderMode::full;
  full.gaze_px.reset();
  say(fmt::format("references: two full frames of {} rays per pixel at {}x{}", p.render.foveation.max_rays, p.render.width,
                  p.render.height));
  const References reference = trace_references(run, p, glm::ivec2(p.render.width, p.render.height));
  const GBuffer& g = reference.g;
  // … and at the smaller sizes a deadline loop traces its view at (a size growing back), on first use
  std::map<std::pair<int, int>, References> smaller;
  const auto references_at = [&](glm::ivec2 size) -> const References& {
    auto [at, fresh] = smaller.try_emplace({size.x, size.y});
    if (fresh) {
      say(fmt::format("references at {}x{}, a size a deadline loop traced its view at: two full frames of {} rays per pixel", size.x,
                      size.y, p.render.foveation.max_rays));
      at->second = trace_references(run, p, size);
    }
    return at->second;
  };
  const Bounds bounds = run.scene->bounds();
  FoveationMaps all = foveation_maps(full, glm::dvec2(p.render.width * 0.5, p.render.height * 0.5));
  std::vector<Ray> sample;
  collect_ao_rays(g, all, resolve_ao_distance(*run.scene, bounds, p.render.ao_distance), surface_epsilon(bounds), p.render.seed, 13,
                  sample);
  const double raw = run.raw_rays_per_ms ? run.raw_rays_per_ms(sample) : 0.0;
  say(fmt::format("raw tracing rate: {:.0f} rays/ms on {} AO rays of the view", raw, sample.size()));
  const std::vector<WatchedThread> watch =
      wall ? threads_to_watch(census, read_machine_threads(), current_process_id(), kWatchedThreads) : std::vector<WatchedThread>{};
  // The model clock: the deadline loop's own rate and fixed cost, measured on this view first
  double model_rate = 0, model_fixed = 0;
  if (p.clock == LoopClock::model && p.model_rays_per_ms && p.model_fixed_ms) {
    model_rate = *p.model_rays_per_ms;
    model_fixed = *p.model_fixed_ms;
    say(fmt::format("model clock: {:.0f} AO rays/ms and {:.2f} ms a frame besides, as given", model_rate, model_fixed));
  } else if (p.clock == LoopClock::model) {
    LoopSettings calib;
    calib.budget_ms = budget;
    RealtimeLoop rt(*run.renderer, *run.scene, p.render, calib);
    rt.frame(run.camera);
    double rays = 0, trace = 0;
    std::vector<double> fixed;
    for (int k = 0; k < 20; ++k) {
      rt.push_gaze(k * 0.05, glm::dvec2((0.2 + 0.03 * k) * p.render.width, 0.5 * p.render.height));
      const LoopFrame f = rt.frame(run.camera);
      rays += static_cast<double>(f.rays);
      trace += f.trace_ms;
      fixed.push_back(f.ms - f.trace_ms);
    }
    model_rate = trace > 0 ? rays / trace : 1;
    model_fixed = quantile(fixed, 0.5);
    say(fmt::format("model clock: {:.0f} AO rays/ms and {:.2f} ms a frame besides, measured on 20 frames", model_rate, model_fixed));
  }
  for (const Recording& rec : recordings) {
    Segment s = make_segment(rec, p);
    if (p.timeline_saccade && &rec == &recordings.front() && !s.saccades.empty())
      s.drawn = std::min(*p.timeline_saccade, s.saccades.size() - 1);
    s.ref = reference.ref;
    s.ref2 = reference.ref2;
    s.render = p.render;
    s.references_at = references_at;
    for (LatencySaccade& sac : s.saccades) {
      s.masks.push_back(fovea_mask(p.render, g, sac.landing_px, s.ref, s.ref2));
      const double rays = static_cast<double>(s.masks.back().pixels.size()) * p.render.foveation.max_rays;
      sac.ray_bound_ms = raw > 0 ? rays / raw : NAN;
      if (p.clock == LoopClock::model) sac.model_ray_bound_ms = rays / model_rate;
    }
    LatencyRecording out;
    out.recording = rec.source;
    out.sampling_hz = rec.rate_hz();
    out.tracker_latency_ms = s.latency_s * 1000;
    out.raw_rays_per_ms = raw;
    out.model_rays_per_ms = model_rate;
    out.model_fixed_ms = model_fixed;
    out.drawn = s.drawn;
    out.begin_s = s.begin;
    out.end_s = s.end;
    out.cut = s.cut;
    for (size_t i = 0; i < s.t.size(); ++i)
      if (s.t[i] >= s.begin - 0.1 && s.t[i] < s.end && s.px[i]) {
        out.gaze_t.push_back(s.t[i]);
        out.gaze_px.push_back(*s.px[i]);
      }
    say(fmt::format("{}: {:.0f} Hz, tracker latency {:.1f} ms, {:.1f}–{:.1f} s{}: {} saccade{} of at least {}°", rec.source,
                    out.sampling_hz, out.tracker_latency_ms, s.begin, s.end, cut_note(s.cut, p), s.saccades.size(),
                    s.saccades.size() == 1 ? "" : "s", p.min_amplitude_deg));
    if (out.gaze_t.empty())
      say(fmt::format("  (no valid gaze sample in {:.1f}–{:.1f} s: the tracker lost the eye throughout; the loops follow no gaze here)",
                      s.begin, s.end));
    for (const std::string& name : p.loops) {
      const Timer timer;
      LatencyLoop loop = name == "whole-frame" ? run_whole_frame(run, s, p, budget, model_rate, model_fixed)
                                               : run_deadline(run, s, p, budget, name, model_rate, model_fixed, watch);
      say(fmt::format("  {}: {} frames ({} late{}), median landing → converged fovea {} ms ({:.1f} s)", name, loop.frames, loop.frames_late,
                      loop.frames_lowered > 0
                          ? fmt::format(", {} at a lowered size{}", loop.frames_lowered,
                                        loop.frames_not_judged > 0 ? fmt::format(", {} of them not judged", loop.frames_not_judged) : "")
                          : "",
                      ms_or_dash(loop.median_converged_ms()), timer.ms() / 1000));
      out.loops.push_back(std::move(loop));
    }
    report.recordings.push_back(std::move(out));
  }
  // Markdown and JSON
  std::string md = fmt::format(
      "Scene {}, {}x{}, n_max {}, device {}, {:.0f} Hz display (budget {:.1f} ms), {} clock{}.\n\n", run.scene_name, p.render.width,
      p.render.height, p.render.foveation.max_rays, run.device, p.refresh_hz, budget, to_string(p.clock),
      fmt::format("{}{}{}",
                  p.periphery_share < 1 ? fmt::format(", the periphery's rays within {:g} % of each budget", 100 * p.periphery_share) : "",
                  p.rays_ahead ? "" : ", no rays ahead of the gaze",
                  p.min_scale != kDefaultMinScale ? fmt::format(", the size no lower than {:g} % of it", 100 * p.min_scale) : ""));
  nlohmann::json j;
  j["scene"] = run.scene_name;
  j["device"] = run.device;
  j["size"] = {p.render.width, p.render.height};
  j["max_rays"] = p.render.foveation.max_rays;
  j["refresh_hz"] = p.refresh_hz;
  j["clock"] = to_string(p.clock);
  j["periphery_share"] = p.periphery_share;  // the deadline loops' (--periphery-share)
  j["rays_ahead"] = p.rays_ahead;            // the deadline loops' (--no-rays-ahead)
  j["min_scale"] = p.min_scale;              // the deadline loops' (--min-scale)
  // the least margin the deadline loops keep (--margin-ms, else the default); the wall clock's alone
  j["margin_ms"] = p.clock == LoopClock::wall ? nlohmann::json(loop_margin_ms(budget, p.margin_ms)) : nlohmann::json(nullptr);
  j["landing"] = nlohmann::json::object();  // the prediction loops' landing predictor (--landing)
  for (const auto& [name, value] : landing_parameters(p.landing)) j["landing"][name] = value;
  j["recordings"] = nlohmann::json::array();
  for (const LatencyRecording& r : report.recordings) {
    std::vector<double> bounds_ms, model_bounds_ms, durations;
    for (const LatencySaccade& sac : r.loops.empty() ? std::vector<LatencySaccade>{} : r.loops.front().saccades) {
      bounds_ms.push_back(sac.ray_bound_ms);
      model_bounds_ms.push_back(sac.model_ray_bound_ms);
      durations.push_back(sac.duration_ms);
    }
    // On the model clock the loops trace at the model's rate, not the raw one: their ratio is to the
    // bound at that rate (against the raw rate a model of half of it read as 2× the bound)
    const bool model = p.clock == LoopClock::model;
    const double bound = quantile(model ? model_bounds_ms : bounds_ms, 0.5);
    md += fmt::format(
        "**{}** ({:.1f}–{:.1f} s{}; {:.0f} Hz, tracker latency {:.1f} ms; {} saccades ≥ {}°, median duration {} ms; raw rate {:.0f} "
        "rays/ms, median ray bound {} ms{})\n\n",
        r.recording, r.begin_s, r.end_s, cut_note(r.cut, p), r.sampling_hz, r.tracker_latency_ms, bounds_ms.size(), p.min_amplitude_deg,
        ms_or_dash(durations.empty() ? NAN : quantile(durations, 0.5)), r.raw_rays_per_ms,
        ms_or_dash(bounds_ms.empty() ? NAN : quantile(bounds_ms, 0.5)),
        model ? fmt::format("; at the model's {:.0f} rays/ms {} ms", r.model_rays_per_ms, ms_or_dash(bounds_ms.empty() ? NAN : bound))
              : std::string());
    md += fmt::format(
        "| loop | frames | late | refreshes missed | frame ms p50 | p99 | landing → converged fovea, median ms | × ray bound{} | "
        "converged while the eye stayed |\n",
        model ? " (model's rate)" : "");
    md += "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    nlohmann::json jr;
    jr["recording"] = r.recording;
    jr["segment_s"] = {r.begin_s, r.end_s};  // seconds from its first sample; cut at its last where asked past it
    jr["segment_cut"] = r.cut;
    jr["sampling_hz"] = r.sampling_hz;
    jr["tracker_latency_ms"] = r.tracker_latency_ms;
    jr["raw_rays_per_ms"] = r.raw_rays_per_ms;
    if (p.clock == LoopClock::model) jr["model"] = {{"rays_per_ms", r.model_rays_per_ms}, {"fixed_ms", r.model_fixed_ms}};
    for (const LatencyLoop& l : r.loops) {
      const auto median = l.median_converged_ms();
      size_t stayed = 0;
      for (const LatencySaccade& sac : l.saccades) stayed += sac.converged_ms && *sac.converged_ms <= sac.fixation_ms ? 1 : 0;
      md += fmt::format("| {} | {} | {} | {} | {:.1f} | {:.1f} | {} | {} | {} of {} |\n", l.name, l.frames, l.frames_late,
                        l.refreshes_missed, l.frame_ms_p50, l.frame_ms_p99, ms_or_dash(median),
                        median && bound > 0 ? fmt::format("{:.2f}", *median / bound) : "—", stayed, l.saccades.size());
      jr[l.name] = loop_json(l);
    }
    md += "\n";
    // Frames at a lowered size: judged against references traced at the size of the view each comes
    // from, on the pixels it shows; any not judged (a frame whose pixels the loop did not say) are
    // counted, and a landing that waited through them may have had its fovea within noise sooner
    // than its figure says
    std::string lowered;
    for (const LatencyLoop& l : r.loops) {
      if (l.frames_lowered == 0) continue;
      size_t waited = 0;
      for (const LatencySaccade& sac : l.saccades) waited += sac.frames_not_judged > 0 ? 1 : 0;
      lowered += fmt::format("{}{}: {} of {} frames{}", lowered.empty() ? "" : "; ", l.name, l.frames_lowered, l.frames,
                             l.frames_not_judged > 0 ? fmt::format(" ({} not judged, {} landing{} waiting through them)",
                                                                   l.frames_not_judged, waited, waited == 1 ? "" : "s")
                                                     : std::string());
    }
    if (!lowered.empty())
      md += fmt::format(
          "Frames at a lowered size, where the loop's fixed part did not fit the budget: {}. Each is judged against references traced "
          "at the size of the view it comes from ({}x{}, or a smaller size the loop traced a view at, growing back: traced for them), "
          "on the pixels it shows, each against the references at the pixel of that view whose surface it shows (`frames_lowered`, "
          "`frames_not_judged` in the JSON; docs/realtime.md).\n\n",
          lowered, p.render.width, p.render.height);
    // What a predictor gains in the median over the loop without one, beside a third of the median
    // saccade (the gain the real-time issue asks for: docs/realtime.md), and a perfect one's
    const auto median_of = [&](const char* name) -> std::optional<double> {
      for (const LatencyLoop& l : r.loops)
        if (l.name == name) return l.median_converged_ms();
      return std::nullopt;
    };
    if (const auto without = median_of("deadline"); without && !durations.empty()) {
      const double third = quantile(durations, 0.5) / 3;
      std::string gains;
      for (const auto& [name, key] :
           {std::pair{"deadline+prediction", "prediction_gain_ms"}, std::pair{"deadline+oracle", "oracle_gain_ms"}})
        if (const auto with = median_of(name)) {
          jr[key] = *without - *with;
          gains += fmt::format("{}{} {:.0f} ms", gains.empty() ? "" : ", ", name, *without - *with);
        }
      if (!gains.empty()) {
        jr["third_of_median_saccade_ms"] = third;
        const std::string slow = late_landing_note(r.sampling_hz);
        md += fmt::format("Gained over the deadline loop's median: {} (a third of the median saccade: {:.0f} ms).{}\n\n", gains, third,
                          slow.empty() ? "" : " Prediction: " + slow + ".");
        if (!slow.empty()) jr["prediction_note"] = slow;
      }
    }
    std::string late, waits;
    for (const LatencyLoop& l : r.loops) {
      if (l.late.empty()) continue;
      late += fmt::format("{}{}: {}", late.empty() ? "" : "; ", l.name, late_summary(l.late));
      const std::string w = late_threads_summary(l.late, l.budget_ms);
      if (!w.empty()) waits += fmt::format("{}{}: {}", waits.empty() ? "" : "; ", l.name, w);
    }
    std::string left;
    for (const LatencyLoop& l : r.loops)
      if (l.frames_left_behind > 0)
        left +=
            fmt::format("{}{}: {}{}", left.empty() ? "" : "; ", l.name,
                        l.frames_left_behind == 1
                            ? fmt::format("1 frame, which would{} have been late had it waited", l.late_had_they_waited == 1 ? "" : " not")
                            : fmt::format("{} frames, {} of which would have been late had they waited", l.frames_left_behind,
                                          l.late_had_they_waited == 0 ? std::string("none") : std::to_string(l.late_had_they_waited)),
                        l.late_had_they_waited > 0 ? fmt::format(" (up to {:.1f} ms longer)", l.most_saved_ms) : "");
    if (!left.empty())
      md += fmt::format("Chunks of rays left to threads the machine had paused, rather than waited for (docs/realtime.md): {}.\n\n", left);
    if (!late.empty()) md += fmt::format("Late frames, where the pause fell (docs/realtime.md): {}.\n\n", late);
    if (!waits.empty()) md += fmt::format("The late frames' threads (docs/realtime.md): {}.\n\n", waits);
    j["recordings"].push_back(jr);
  }
  report.markdown = md;
  report.json = j;
  report.others = busiest_others(census, read_machine_threads(), current_process_id(), kBusiestOthers);
  return report;
}

LatencyReport bench_latency(const Scene& scene, const std::string& scene_name, const Camera& camera, ComputeDevice device, int threads,
                            const std::vector<Recording>& recordings, const LatencyParams& params,
                            const std::function<void(const std::string&)>& say) {
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(scene, device);
  LatencyRun run;
  run.renderer = renderer.get();
  run.scene = &scene;
  run.camera = camera;
  run.scene_name = scene_name;
  run.device = fmt::format("{} ({} threads)", renderer->describe(), threads);
  // The raw rate of the device the loops render on: Embree's on the CPU, the GPU's own kernel
  run.raw_rays_per_ms = [&](std::span<const Ray> rays) { return renderer->raw_occlusion_rays_per_ms(rays); };
  run.say = say;  // (none: no progress lines)
  if (say) say(fmt::format("foveal bench latency: {} on {}", scene_name, run.device));
  const CpuTimes before = read_cpu_times();
  LatencyReport report = run_latency_bench(run, recordings, params);
  // What else ran: a frame comes late when another process or the hypervisor takes its core
  const CpuShare share = cpu_share(before, read_cpu_times());
  if (std::isfinite(share.others)) {
    const KernelScheduling kernel = read_kernel_scheduling();
    report.json["machine"] = {{"others_cpu_fraction", share.others},
                              {"steal_fraction", share.steal},
                              {"others", others_json(report.others)},
                              {"kernel", kernel_json(kernel)}};
    if (!report.markdown.ends_with("\n\n")) report.markdown += "\n";
    report.markdown += fmt::format(
        "The machine during the run: other processes kept {:.0f} % of all CPUs' time busy, the hypervisor took {:.0f} % "
        "(steal){}.\n",
        100 * share.others, 100 * share.steal,
        share.others > 0.05 || share.steal > 0.01 ? ": wall-clock late frames may be theirs, not the loop's" : "");
    if (!report.others.empty()) report.markdown += fmt::format("What else ran, the busiest first: {}.\n", others_sentence(report.others));
    if (params.clock == LoopClock::wall) {  // (how long another thread may keep a core, against the loops' margin)
      const double margin = loop_margin_ms(frame_budget(params), params.margin_ms);
      if (const std::string k = kernel_sentence(kernel, margin); !k.empty()) report.markdown += k + "\n";
    }
  }
  return report;
}

namespace {

// Where `drawn`'s fovea was ready at its landing in every deadline loop, its picture shows no wait:
// the saccade the first deadline loop waited longest for instead ('' where the picture shows a wait)
std::string no_wait_note(const LatencyRecording& r, size_t drawn, const std::string& option) {
  const auto wait_ms = [](const LatencySaccade& s) { return s.converged_ms.value_or(INFINITY); };
  const LatencyLoop* first = nullptr;
  for (const LatencyLoop& loop : r.loops) {
    if (loop.name == "whole-frame" || drawn >= loop.saccades.size()) continue;
    if (wait_ms(loop.saccades[drawn]) > 0) return "";  // the picture shows this loop waiting
    if (!first) first = &loop;
  }
  if (!first) return "";
  size_t longest = drawn;
  for (size_t k = 0; k < first->saccades.size(); ++k)
    if (wait_ms(first->saccades[k]) > wait_ms(first->saccades[longest])) longest = k;
  const std::string picture =
      fmt::format("saccade {}'s fovea was ready at its landing in every deadline loop, so its picture shows no wait", drawn);
  if (longest == drawn) return picture + fmt::format(" (nor did any other landing in {}'s segment wait)", r.recording);
  const std::optional<double> ms = first->saccades[longest].converged_ms;
  return picture + fmt::format("; the {} loop waited longest for saccade {} ({}): {}{}", first->name, longest,
                               ms ? fmt::format("{:.0f} ms", *ms) : std::string("not converged within the segment"), option, longest);
}

}  // namespace

std::string latency_timeline_note(const LatencyReport& report, size_t asked, const std::string& option) {
  if (report.recordings.empty() || !report.recordings.front().drawn) return "";
  const LatencyRecording& r = report.recordings.front();
  const size_t drawn = *r.drawn;
  std::vector<std::string> parts;
  if (asked > drawn)
    parts.push_back(fmt::format("saccade {} was asked for, and {}'s segment judged {} (0–{}): the last is drawn", asked, r.recording,
                                drawn + 1, drawn));
  if (std::string note = no_wait_note(r, drawn, option); !note.empty()) parts.push_back(std::move(note));
  return fmt::format("{}", fmt::join(parts, "; "));
}

size_t write_latency_timeline(const LatencyReport& report, double min_amplitude_deg, const std::string& path) {
  if (report.recordings.empty()) fail("timeline: no recording");
  const LatencyRecording& r = report.recordings.front();
  if (r.loops.empty() || r.loops.front().saccades.empty())
    fail("timeline: no saccade of at least {}° lands in {}'s segment", min_amplitude_deg, r.recording);
  if (!r.drawn) fail("timeline: the run did not judge a saccade for the picture (LatencyParams::timeline_saccade)");
  const size_t saccade = *r.drawn;
  const LatencySaccade& sac = r.loops.front().saccades[saccade];
  const double t0 = sac.landing_s - sac.duration_ms / 1000 - 0.1, t1 = sac.landing_s + 0.35;
  Plot plot;
  plot.width = 900;
  plot.height = 600;
  const float left = 70, right = 880, top = 50, mid = 300, bottom = 500;
  const auto x_of = [&](double t) { return left + static_cast<float>((t - t0) / (t1 - t0)) * (right - left); };
  // Top: the gaze's horizontal position and where each loop placed the fovea (render pixels)
  double lo = 1e30, hi = -1e30;
  for (size_t i = 0; i < r.gaze_t.size(); ++i)
    if (r.gaze_t[i] >= t0 && r.gaze_t[i] <= t1) lo = std::min(lo, r.gaze_px[i].x), hi = std::max(hi, r.gaze_px[i].x);
  if (!(hi > lo)) lo = 0, hi = 1;
  const double pad = 0.15 * (hi - lo);
  lo -= pad, hi += pad;
  const auto y_top = [&](double x) { return mid - 20 - static_cast<float>((std::clamp(x, lo, hi) - lo) / (hi - lo)) * (mid - 20 - top); };
  Stroke gaze{{}, {0.1f, 0.1f, 0.1f}, 2.5f};
  for (size_t i = 0; i < r.gaze_t.size(); ++i)
    if (r.gaze_t[i] >= t0 && r.gaze_t[i] <= t1) gaze.points.emplace_back(x_of(r.gaze_t[i]), y_top(r.gaze_px[i].x));
  plot.strokes.push_back(gaze);
  // Each loop's colour follows its name, whichever loops ran (as docs/realtime.md's pictures show them)
  const auto colour_of = [](const std::string& loop) -> glm::vec3 {
    if (loop == "whole-frame") return {0.6f, 0.6f, 0.6f};
    if (loop == "deadline") return {0.15f, 0.45f, 0.85f};
    if (loop == "deadline+prediction") return {0.85f, 0.35f, 0.1f};
    return {0.55f, 0.2f, 0.65f};  // deadline+oracle
  };
  // Bottom: this saccade's landed fovea's error per shown frame, before the landing too (× the
  // reference's noise, log scale 0.5–64)
  const auto y_bottom = [&](double e) {
    const double l = std::clamp(std::log2(std::max(e, 0.5)), -1.0, 6.0);
    return bottom - static_cast<float>((l + 1) / 7) * (bottom - mid - 30);
  };
  for (size_t k = 0; k < r.loops.size(); ++k) {
    const glm::vec3 colour = colour_of(r.loops[k].name);
    Stroke place{{}, colour, 1.5f, false}, err{{}, colour, 2};
    for (const LatencyFrame& f : r.loops[k].timeline) {
      if (f.shown_s < t0 || f.start_s > t1) continue;
      const double a = std::max(f.start_s, t0), b = std::min(f.shown_s, t1);
      place.points.emplace_back(x_of(a), y_top(f.gaze_px.x));
      place.points.emplace_back(x_of(b), y_top(f.gaze_px.x));
      if (std::isfinite(f.drawn_error) && f.shown_s <= t1) err.points.emplace_back(x_of(f.shown_s), y_bottom(f.drawn_error));
    }
    plot.strokes.push_back(place);
    plot.strokes.push_back(err);
    const float ly = bottom + 48 + 18.0f * static_cast<float>(k);
    plot.strokes.push_back({{{left, ly - 5}, {left + 30, ly - 5}}, colour, 3});
    plot.labels.push_back({{left + 40, ly}, r.loops[k].name});
  }
  plot.strokes.push_back({{{x_of(sac.landing_s), top}, {x_of(sac.landing_s), bottom}}, {0.2f, 0.6f, 0.2f}, 1, true});
  plot.strokes.push_back({{{left, y_bottom(1)}, {right, y_bottom(1)}}, {0.2f, 0.6f, 0.2f}, 1, true});
  plot.labels.push_back({{x_of(sac.landing_s) + 4, top + 12}, "landing"});
  const std::string name = std::filesystem::path(r.recording).filename().string();
  plot.labels.push_back(
      {{left, top - 28},
       fmt::format("{}: a {:.1f} deg saccade. Gaze x (black, render px) and where each loop put the fovea", name, sac.amplitude_deg)});
  plot.labels.push_back({{left, mid + 4}, "Its landed fovea's error per shown frame, x the reference's noise (log, 0.5 to 64; green: 1)"});
  plot.labels.push_back({{left, bottom + 22}, fmt::format("time {:.2f} to {:.2f} s; each loop's frames as shown", t0, t1)});
  save_plot(plot, path);
  return saccade;
}

}  // namespace foveal
