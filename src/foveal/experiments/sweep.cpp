// foveal/experiments/sweep.cpp — see sweep.h.
#include "foveal/experiments/sweep.h"

#include "foveal/io/plot.h"
#include "foveal/experiments/ao_benchmark.h"
#include "foveal/trace/tracer.h"
#include "foveal/util/error.h"
#include <tbb/global_control.h>
#include "foveal/util/stats.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace foveal {
namespace {

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(v > 0 ? "inf" : "-inf"); }

int band_index(const std::vector<std::string>& names, const std::string& name) {
  for (size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return static_cast<int>(k);
  return -1;
}

}  // namespace

QualitySweepResult run_quality_sweep(const Scene& scene, const Tracer& tracer, const Camera& camera, const QualitySweepParams& params,
                                     const std::function<void(const std::string&)>& progress) {
  auto say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  if (params.gazes.empty()) fail("bench quality: no gaze point");
  if (params.gammas.empty() || params.max_rays.empty() || params.betas.empty() || params.methods.empty())
    fail("bench quality: --gamma, --max-rays, --beta and --configs need at least one value each");
  for (const ReuseConfig& m : params.methods)
    if (m.reuse.temporal) fail("bench quality: {} reuses earlier frames; single frames have none (use --sequence)", m.name);
  for (int n : params.max_rays)
    if (n < 1) fail("max_rays: every value must be at least 1, got {}", n);
  RenderParams base = params.render;
  base.seed = params.seed;
  validate(base);
  // Every value of the grid, checked before hours of rendering (validate names the option)
  for (double g : params.gammas) {
    RenderParams check = base;
    check.foveation.gamma = g;
    validate(check);
  }
  for (double b : params.betas) {
    RenderParams check = base;
    check.foveation.beta = b;
    validate(check);
  }
  for (int n : params.max_rays) {
    RenderParams check = base;
    check.foveation.max_rays = n;
    check.foveation.min_rays = std::min(check.foveation.min_rays, n);
    validate(check);
  }
  for (const ReuseConfig& m : params.methods) {
    RenderParams check = base;
    check.reuse = m.reuse;
    check.reuse.target_rays = params.reference_rays;
    validate(check);
  }

  QualitySweepResult result;
  result.scene = scene.source;
  result.camera = params.camera_name;
  result.width = base.width;
  result.height = base.height;
  result.reference_rays = params.reference_rays;
  result.saccade_deg = params.saccade_deg;
  result.threads = static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  result.triangles = tracer.triangles();
  for (const Band& b : default_bands()) result.band_names.push_back(b.name);

  // The full-frame reference and a second one of another seed (its own noise); gaze-independent
  RenderParams full = base;
  full.mode = RenderMode::full;
  full.foveation.max_rays = params.reference_rays;
  full.foveation.min_rays = std::min(full.foveation.min_rays, params.reference_rays);
  full.seed = params.seed + 1;
  const Frame reference = timed_frame(tracer, scene, camera, full, params.repeats, result.reference_ms);
  result.reference_ao_rays = reference.stats.ao_rays;
  full.seed = params.seed + 2;
  // The reference's own noise: per pixel, the same for every configuration and gaze
  const ReferenceNoise noise = reference_noise(render_frame(tracer, scene, camera, full).color, reference.color);
  say(fmt::format("reference: full frame, {} rays per pixel, {:.0f} ms, {:.1f} M AO rays", params.reference_rays, result.reference_ms,
                  reference.stats.ao_rays * 1e-6));
  for (const auto& [label, gaze] : params.gazes) {
    const FoveationMaps maps = foveation_maps(base, gaze);
    FoveaFloor f;
    f.gaze_label = label;
    double sum_sigma = 0, sum_variance = 0;
    for (size_t i = 0; i < maps.quality.size(); ++i) {
      if (maps.quality[i] < 1.0f || reference.gbuffer.prim[i] == Hit::kNoHit) continue;
      ++f.fovea_pixels;
      const double v = reference.visibility[i];
      if (v > 0.0 && v < 1.0) ++f.partly_occluded;
      sum_sigma += std::sqrt(v * (1.0 - v));
      sum_variance += v * (1.0 - v);
    }
    f.min_rays = sum_variance > 0 ? params.reference_rays * sum_sigma * sum_sigma / sum_variance : 0.0;
    f.ray_ratio_bound =
        f.min_rays > 0 ? static_cast<double>(result.reference_ao_rays) / f.min_rays : std::numeric_limits<double>::infinity();
    result.fovea_floors.push_back(f);
  }

  const Bounds bounds = scene.bounds();
  const float epsilon = surface_epsilon(bounds);
  for (double gamma : params.gammas)
    for (int n_max : params.max_rays)
      for (const ReuseConfig& method : params.methods) {
        const size_t first = result.points.size();
        for (double beta : params.betas) {
          QualityPoint q;
          q.gamma = gamma, q.max_rays = n_max, q.beta = beta, q.method = method.name;
          result.points.push_back(q);
        }
        for (const auto& [label, gaze] : params.gazes) {
          RenderParams p = base;
          p.mode = RenderMode::foveated;
          p.gaze_px = gaze;
          p.foveation.gamma = gamma;
          p.foveation.max_rays = n_max;
          p.foveation.min_rays = std::min(p.foveation.min_rays, n_max);
          p.foveation.beta = params.betas.front();
          p.reuse = method.reuse;
          p.reuse.target_rays = params.reference_rays;  // τ(E) from the noise of the reference judged against
          double ms = 0;
          const Frame frame = timed_frame(tracer, scene, camera, p, params.repeats, ms);
          // The frame after a saccade to the right (to the left when that leaves the image)
          const double shift = params.saccade_deg * pixels_per_degree(p.display) * p.width / p.display.res_x;
          RenderParams after = p;
          after.gaze_px = glm::dvec2(gaze.x + shift <= p.width ? gaze.x + shift : gaze.x - shift, gaze.y);
          const Frame next = render_frame(tracer, scene, camera, after);
          for (size_t k = 0; k < params.betas.size(); ++k) {
            p.foveation.beta = after.foveation.beta = params.betas[k];
            // Another β: the same rays and visibility, another blend (the maps' blend is the only change)
            Image image, image_after;
            if (k == 0) {
              image = frame.color;
              image_after = next.color;
            } else {
              image = shade(tracer, scene, camera, frame.gbuffer, foveation_maps(p, gaze), frame.visibility, frame.stats.ambient_constant,
                            p.shadows, epsilon);
              image_after = shade(tracer, scene, camera, next.gbuffer, foveation_maps(after, *after.gaze_px), next.visibility,
                                  next.stats.ambient_constant, p.shadows, epsilon);
            }
            const Comparison c = compare_images(image, reference.color, noise, p.display, gaze, p.foveation);
            const double flicker = acuity_weighted_rmse(image_after, image, c.quality);
            QualityGazeResult g;
            g.gaze_label = label;
            g.gaze_px = gaze;
            g.ms = ms;
            g.ao_rays = frame.stats.ao_rays;
            g.weighted_rmse = c.weighted_rmse;
            g.weighted_ratio = c.weighted_ratio();
            g.weighted_noise_rmse = c.weighted_noise_rmse;
            g.flicker_rmse = flicker;
            g.flicker_ratio = c.weighted_noise_rmse > 0 ? flicker / c.weighted_noise_rmse : 0.0;
            g.bands = c.bands;
            g.whole = c.whole;
            result.points[first + k].per_gaze.push_back(g);
          }
        }
        double mean_ms = 0;
        for (const QualityGazeResult& g : result.points[first].per_gaze) mean_ms += g.ms / params.gazes.size();
        say(fmt::format("gamma {:g}, n_max {}, {}: {:.0f} ms per frame (mean over {} gaze point(s)), {} betas judged", gamma, n_max,
                        method.name, mean_ms, params.gazes.size(), params.betas.size()));
      }

  // Means over the gaze points
  const size_t bands = result.band_names.size();
  for (QualityPoint& q : result.points) {
    const double g = static_cast<double>(q.per_gaze.size());
    double ms = 0, rays = 0;
    q.band_ratio.assign(bands, 0.0);
    q.band_rmse.assign(bands, 0.0);
    std::vector<int> band_gazes(bands, 0);
    q.fovea_within_noise = true;
    for (const QualityGazeResult& r : q.per_gaze) {
      ms += r.ms;
      rays += static_cast<double>(r.ao_rays);
      q.weighted_ratio += r.weighted_ratio / g;
      q.weighted_rmse += r.weighted_rmse / g;
      q.flicker_ratio += r.flicker_ratio / g;
      for (size_t k = 0; k < bands; ++k) {
        const BandResult& b = r.bands[k];
        if (b.error.pixels == 0) continue;
        q.band_ratio[k] += b.noise_ratio;
        q.band_rmse[k] += b.error.rmse;
        ++band_gazes[k];
        if (b.band.foveal_region && !b.within_noise) q.fovea_within_noise = false;
      }
    }
    for (size_t k = 0; k < bands; ++k)
      if (band_gazes[k] > 0)
        q.band_ratio[k] /= band_gazes[k], q.band_rmse[k] /= band_gazes[k];
      else
        q.band_ratio[k] = q.band_rmse[k] = std::nan("");
    q.ms = ms / g;
    q.speedup = q.ms > 0 ? result.reference_ms / q.ms : 0.0;
    q.ray_ratio = rays > 0 ? static_cast<double>(result.reference_ao_rays) * g / rays : std::numeric_limits<double>::infinity();
  }
  for (const QualityGazeResult& r : result.points.front().per_gaze)
    result.reference_noise_weighted_rmse += r.weighted_noise_rmse / static_cast<double>(params.gazes.size());
  mark_pareto_front(result.points);
  return result;
}

void mark_pareto_front(std::vector<QualityPoint>& points) {
  for (QualityPoint& p : points) {
    p.pareto = true;
    for (const QualityPoint& o : points) {
      const bool no_worse = o.speedup >= p.speedup && o.weighted_ratio <= p.weighted_ratio && o.flicker_ratio <= p.flicker_ratio;
      const bool better = o.speedup > p.speedup || o.weighted_ratio < p.weighted_ratio || o.flicker_ratio < p.flicker_ratio;
      if (&o != &p && no_worse && better) {
        p.pareto = false;
        break;
      }
    }
  }
}

int recommended_point(const std::vector<QualityPoint>& points, double max_weighted_ratio, double max_flicker_ratio) {
  int best = -1;
  for (size_t k = 0; k < points.size(); ++k) {
    const QualityPoint& p = points[k];
    if (!p.fovea_within_noise || !(p.weighted_ratio <= max_weighted_ratio) || !(p.flicker_ratio <= max_flicker_ratio)) continue;
    if (best < 0 || p.speedup > points[best].speedup ||
        (p.speedup == points[best].speedup && p.weighted_ratio < points[best].weighted_ratio))
      best = static_cast<int>(k);
  }
  return best;
}

nlohmann::json to_json(const QualitySweepResult& r) {
  nlohmann::json j = {{"scene", r.scene},
                      {"camera", r.camera},
                      {"width", r.width},
                      {"height", r.height},
                      {"triangles", r.triangles},
                      {"threads", r.threads},
                      {"reference_rays", r.reference_rays},
                      {"saccade_deg", r.saccade_deg},
                      {"reference_ms", r.reference_ms},
                      {"reference_ao_rays", r.reference_ao_rays},
                      {"reference_noise_weighted_rmse", r.reference_noise_weighted_rmse},
                      {"bands", r.band_names},
                      {"fovea_floors", nlohmann::json::array()},
                      {"points", nlohmann::json::array()}};
  for (const FoveaFloor& f : r.fovea_floors)
    j["fovea_floors"].push_back({{"gaze", f.gaze_label},
                                 {"fovea_pixels", f.fovea_pixels},
                                 {"partly_occluded", f.partly_occluded},
                                 {"min_rays", f.min_rays},
                                 {"ray_ratio_bound", number(f.ray_ratio_bound)}});
  for (const QualityPoint& q : r.points) {
    nlohmann::json p = {{"gamma", q.gamma},
                        {"max_rays", q.max_rays},
                        {"beta", q.beta},
                        {"method", q.method},
                        {"ms", q.ms},
                        {"speedup", q.speedup},
                        {"ray_ratio", number(q.ray_ratio)},
                        {"weighted_rmse", q.weighted_rmse},
                        {"weighted_ratio", q.weighted_ratio},
                        {"flicker_ratio", q.flicker_ratio},
                        {"fovea_within_noise", q.fovea_within_noise},
                        {"pareto", q.pareto},
                        {"band_ratio", nlohmann::json::array()},
                        {"band_rmse", nlohmann::json::array()},
                        {"gazes", nlohmann::json::array()}};
    for (size_t k = 0; k < q.band_ratio.size(); ++k) {
      p["band_ratio"].push_back(number(q.band_ratio[k]));
      p["band_rmse"].push_back(number(q.band_rmse[k]));
    }
    for (const QualityGazeResult& g : q.per_gaze) {
      nlohmann::json gj = {{"label", g.gaze_label},          {"gaze_px", {g.gaze_px.x, g.gaze_px.y}}, {"ms", g.ms},
                           {"ao_rays", g.ao_rays},           {"weighted_rmse", g.weighted_rmse},      {"weighted_ratio", g.weighted_ratio},
                           {"flicker_rmse", g.flicker_rmse}, {"flicker_ratio", g.flicker_ratio},      {"psnr", number(g.whole.psnr)},
                           {"ssim", g.whole.ssim},           {"bands", nlohmann::json::array()}};
      for (const BandResult& b : g.bands)
        gj["bands"].push_back({{"name", b.band.name},
                               {"pixels", b.error.pixels},
                               {"rmse", b.error.rmse},
                               {"noise_rmse", b.noise ? b.noise->rmse : 0.0},
                               {"noise_ratio", number(b.noise_ratio)},
                               {"within_noise", b.within_noise}});
      p["gazes"].push_back(gj);
    }
    j["points"].push_back(p);
  }
  return j;
}

std::string to_markdown(const QualitySweepResult& r) {
  std::string out = fmt::format(
      "{} ({} triangles), camera {}, {}x{}; reference: full frame with {} rays per pixel, {:.0f} ms ({} threads). "
      "Speed-up = reference time / foveated time (mean over the gaze points); errors are RMSE against the reference as "
      "a multiple of the reference's own seed-to-seed RMSE (1 = indistinguishable from its noise), mean over the gaze "
      "points; the acuity-weighted error weights each pixel by q(E)²; flicker is the acuity-weighted change after a "
      "{:g}° saccade (the reference does not change), in the same unit. ● = on the Pareto front (speed-up, error, "
      "flicker); ✓ = the q(E) = 1 region within the reference's noise at every gaze point.\n\n",
      r.scene, r.triangles, r.camera.empty() ? "(default)" : r.camera, r.width, r.height, r.reference_rays, r.reference_ms, r.threads,
      r.saccade_deg);
  bool methods = false;
  for (const QualityPoint& q : r.points) methods |= q.method != "paper";
  if (!r.fovea_floors.empty()) {
    out +=
        "No method that leaves the fovea unfiltered and keeps it within the reference's noise casts fewer rays than the "
        "q(E) = 1 region's N·(Σσ)²/Σσ² (σ² = V(1 − V) of the reference's pixels there, rays spread ∝ σ): its AO ray ratio is "
        "at most ";
    for (size_t k = 0; k < r.fovea_floors.size(); ++k) {
      const FoveaFloor& f = r.fovea_floors[k];
      out += fmt::format("{}{:.2f} at {} ({} of {} pixels partly occluded)", k ? ", " : "", f.ray_ratio_bound, f.gaze_label,
                         f.partly_occluded, f.fovea_pixels);
    }
    out += ".\n\n";
  }
  out += methods ? "| method | γ | n_max | β |" : "| γ | n_max | β |";
  out += " ms | speed-up | AO ray ratio | acuity-weighted × noise | flicker × noise | q(E) = 1 |";
  std::string rule = methods ? "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|" : "|---:|---:|---:|---:|---:|---:|---:|---:|---|";
  std::vector<size_t> shown;
  for (size_t k = 0; k < r.band_names.size(); ++k)
    if (r.band_names[k] != "q=1") {
      out += fmt::format(" {}° |", r.band_names[k]);
      rule += "---:|";
      shown.push_back(k);
    }
  out += " front |\n" + rule + "---|\n";
  const int fovea = band_index(r.band_names, "q=1");
  for (const QualityPoint& q : r.points) {
    auto ratio = [](double v) { return std::isfinite(v) ? fmt::format("{:.2f}", v) : std::string("–"); };
    if (methods) out += fmt::format("| {} ", q.method);
    out += fmt::format("| {:g} | {} | {:g} | {:.0f} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {} {} |", q.gamma, q.max_rays, q.beta, q.ms,
                       q.speedup, q.ray_ratio, q.weighted_ratio, q.flicker_ratio, fovea >= 0 ? ratio(q.band_ratio[fovea]) : "",
                       q.fovea_within_noise ? "✓" : "✗");
    for (size_t k : shown) out += fmt::format(" {} |", ratio(q.band_ratio[k]));
    out += fmt::format(" {} |\n", q.pareto ? "●" : "");
  }
  return out;
}

namespace {

// A point's marker: a circle for the first method, then a square, a triangle, a diamond, a pentagon.
Stroke marker(size_t method, glm::vec2 c, float radius, glm::vec3 colour, float width) {
  struct Shape {
    int corners;
    float turn;  // radians
  };
  constexpr Shape shapes[] = {{16, 0.0f}, {4, 0.785398f}, {3, -1.570796f}, {4, 0.0f}, {5, -1.570796f}};
  const Shape shape = shapes[method % std::size(shapes)];
  Stroke s{{}, colour, width, false};
  const int corners = shape.corners;
  const float turn = shape.turn;
  const float r = method == 0 ? radius : radius * 1.25f;
  for (int k = 0; k <= corners; ++k) {
    const float a = turn + 6.283185f * k / corners;
    s.points.push_back(c + r * glm::vec2(std::cos(a), std::sin(a)));
  }
  return s;
}

std::vector<std::string> method_names(const QualitySweepResult& r) {
  std::vector<std::string> names;
  for (const QualityPoint& q : r.points)
    if (std::find(names.begin(), names.end(), q.method) == names.end()) names.push_back(q.method);
  return names;
}

// "g2 n400 b0", then the method's options by initial ("t+a+d" for temporal+adaptive+denoise).
std::string point_label(const QualityPoint& q) {
  std::string label = fmt::format("g{:g} n{} b{:g}", q.gamma, q.max_rays, q.beta);
  if (q.method == "paper") return label;
  label += ' ';
  for (size_t k = 0; k < q.method.size(); ++k)
    if (k == 0 || q.method[k - 1] == '+')
      label += q.method[k];
    else if (q.method[k] == '+')
      label += '+';
  return label;
}

// One panel of the Pareto plot: speed-up (x) against `error(point)` (y), both on log scales, at
// horizontal offset `x0`; the two-way front of this panel joined.
void pareto_panel(Plot& plot, float x0, const QualitySweepResult& r, const std::function<double(const QualityPoint&)>& error,
                  const std::string& title, double hg, int hn, double hb, const std::function<glm::vec3(double)>& beta_colour) {
  const float left = x0 + 70, right = x0 + 520, upper = 50, bottom = 440;
  double x_max = 1, y_min = 1e300, y_max = 0;
  for (const QualityPoint& q : r.points) {
    x_max = std::max(x_max, q.speedup);
    if (error(q) > 0) y_min = std::min(y_min, error(q)), y_max = std::max(y_max, error(q));
  }
  if (!(y_max > 0)) y_min = 1, y_max = 2;
  // Speed-up from 1/2 to the power of two above the fastest; the error from a power of two at or
  // below 1 (the reference's own noise) to one above the largest
  const double lx0 = -1, lx1 = std::max(1.0, std::ceil(std::log2(x_max * 1.05)));
  const double ly0 = std::min(0.0, std::floor(std::log2(y_min))), ly1 = std::max(ly0 + 1, std::ceil(std::log2(y_max)));
  auto px = [&](double s, double e) {
    const double lx = std::log2(std::max(s, 1e-9)), ly = std::clamp(std::log2(std::max(e, 1e-9)), ly0, ly1);
    return glm::vec2(left + (right - left) * (lx - lx0) / (lx1 - lx0), bottom - (bottom - upper) * (ly - ly0) / (ly1 - ly0));
  };
  const double x_lo = std::exp2(lx0), x_hi = std::exp2(lx1), y_lo = std::exp2(ly0), y_hi = std::exp2(ly1);
  const glm::vec3 black(0), grey(0.6f);
  plot.strokes.push_back({{glm::vec2(left, upper), glm::vec2(left, bottom), glm::vec2(right, bottom)}, black, 1.5f, false});
  for (double lx = lx0; lx <= lx1; ++lx) {
    const glm::vec2 at = px(std::exp2(lx), y_lo);
    plot.strokes.push_back({{at, at + glm::vec2(0, 6)}, black, 1, false});
    plot.labels.push_back({at + glm::vec2(0, 22), fmt::format("{:g}", std::exp2(lx)), 13, true});
  }
  for (double ly = ly0; ly <= ly1; ++ly) {
    const glm::vec2 at = px(x_lo, std::exp2(ly));
    plot.strokes.push_back({{at, at - glm::vec2(6, 0)}, black, 1, false});
    plot.labels.push_back({at - glm::vec2(50, -5), fmt::format("{:g}", std::exp2(ly)), 12, false});
  }
  // The reference's own noise (1) and the full frame's speed (1)
  plot.strokes.push_back({{px(x_lo, 1), px(x_hi, 1)}, grey, 1, true});
  plot.strokes.push_back({{px(1, y_lo), px(1, y_hi)}, grey, 1, true});
  const std::vector<std::string> methods = method_names(r);
  for (const QualityPoint& q : r.points) {
    const glm::vec2 c = px(q.speedup, error(q));
    const size_t m = std::find(methods.begin(), methods.end(), q.method) - methods.begin();
    plot.strokes.push_back(marker(m, c, 4, beta_colour(q.beta), 2));
    if (!q.fovea_within_noise) plot.strokes.push_back({{c - glm::vec2(3, 3), c + glm::vec2(3, 3)}, black, 1, false});
    if (q.method == "paper" && q.gamma == hg && q.max_rays == hn && q.beta == hb) plot.strokes.push_back(marker(0, c, 9, black, 1.5f));
  }
  // This panel's front (speed-up against its error), joined in order of speed-up and labelled
  std::vector<const QualityPoint*> front;
  for (const QualityPoint& q : r.points) {
    bool dominated = false;
    for (const QualityPoint& o : r.points)
      dominated |= o.speedup >= q.speedup && error(o) <= error(q) && (o.speedup > q.speedup || error(o) < error(q));
    if (!dominated) front.push_back(&q);
  }
  std::sort(front.begin(), front.end(), [](auto* a, auto* b) { return a->speedup < b->speedup; });
  Stroke line{{}, glm::vec3(0.2f), 1.5f, false};
  for (size_t k = 0; k < front.size(); ++k) {
    const glm::vec2 at = px(front[k]->speedup, error(*front[k]));
    line.points.push_back(at);
    const glm::vec2 offset = k % 2 ? glm::vec2(-20, 22) : glm::vec2(-20, -12);  // alternate above and below
    plot.labels.push_back({at + offset, point_label(*front[k]), 10, false});
  }
  plot.strokes.push_back(line);
  plot.labels.push_back({glm::vec2((left + right) / 2, bottom + 48), "speed-up over the full-frame reference (log)", 14, true});
  plot.labels.push_back({glm::vec2(left - 40, upper - 24), title, 13, false});
}

}  // namespace

void write_pareto_plot(const QualitySweepResult& r, const std::string& path, double hg, int hn, double hb) {
  Plot plot;
  plot.width = 1300;
  plot.height = 520;
  std::vector<double> betas;
  for (const QualityPoint& q : r.points)
    if (std::find(betas.begin(), betas.end(), q.beta) == betas.end()) betas.push_back(q.beta);
  std::sort(betas.begin(), betas.end());
  auto beta_colour = [&](double b) {
    const size_t k = std::find(betas.begin(), betas.end(), b) - betas.begin();
    const float t = betas.size() > 1 ? static_cast<float>(k) / (betas.size() - 1) : 0.0f;
    return glm::mix(glm::vec3(0.1f, 0.35f, 0.85f), glm::vec3(0.85f, 0.2f, 0.1f), t);
  };
  pareto_panel(
      plot, 0, r, [](const QualityPoint& q) { return q.weighted_ratio; }, "still image: acuity-weighted error / reference noise (log)", hg,
      hn, hb, beta_colour);
  pareto_panel(
      plot, 560, r, [](const QualityPoint& q) { return q.flicker_ratio; },
      r.saccade_deg > 0 ? fmt::format("flicker after a {:g} deg saccade / reference noise (log)", r.saccade_deg)
                        : std::string("flicker between consecutive frames / reference noise (log)"),
      hg, hn, hb, beta_colour);
  // Legend
  const float x = 1130;
  float y = 60;
  for (double b : betas) {
    plot.strokes.push_back(marker(0, glm::vec2(x, y - 4), 4, beta_colour(b), 2));
    plot.labels.push_back({glm::vec2(x + 12, y), fmt::format("beta = {:g}", b), 12, false});
    y += 20;
  }
  const std::vector<std::string> methods = method_names(r);
  if (methods.size() > 1)
    for (size_t m = 0; m < methods.size(); ++m) {
      plot.strokes.push_back(marker(m, glm::vec2(x, y - 4), 4, glm::vec3(0.3f), 2));
      plot.labels.push_back({glm::vec2(x + 12, y), methods[m], 10, false});
      y += 20;
    }
  plot.strokes.push_back(marker(0, glm::vec2(x, y - 4), 9, glm::vec3(0), 1.5f));
  plot.labels.push_back({glm::vec2(x + 14, y), fmt::format("default g{:g} n{} b{:g}", hg, hn, hb), 11, false});
  y += 22;
  plot.strokes.push_back({{glm::vec2(x - 3, y - 7), glm::vec2(x + 3, y - 1)}, glm::vec3(0), 1, false});
  plot.labels.push_back({glm::vec2(x + 12, y), "fovea outside noise", 11, false});
  y += 24;
  plot.labels.push_back({glm::vec2(x - 10, y), "line: each panel's", 11, false});
  plot.labels.push_back({glm::vec2(x - 10, y + 16), "Pareto front", 11, false});
  plot.labels.push_back({glm::vec2(x - 10, y + 40), "g = gamma, n = n_max", 11, false});
  plot.labels.push_back({glm::vec2(x - 10, y + 56), "b = beta", 11, false});
  if (methods.size() > 1) {
    plot.labels.push_back({glm::vec2(x - 10, y + 72), "a = adaptive, d = denoise,", 11, false});
    plot.labels.push_back({glm::vec2(x - 10, y + 88), "t = temporal", 11, false});
  }
  save_plot(plot, path);
}

QualitySweepResult sequence_points(const QualitySequenceResult& sequence, const FoveationParams& foveation) {
  QualitySweepResult r;
  r.scene = sequence.scene;
  r.width = sequence.width;
  r.height = sequence.height;
  r.reference_rays = sequence.reference_rays;
  r.threads = sequence.threads;
  r.reference_ms = sequence.reference_ms;
  r.band_names = sequence.band_names;
  for (const SequenceConfigResult& c : sequence.configs) {
    QualityPoint q;
    q.gamma = foveation.gamma, q.max_rays = foveation.max_rays, q.beta = foveation.beta, q.method = c.name;
    q.ms = c.ms, q.speedup = c.speedup, q.ray_ratio = c.ray_ratio;
    q.weighted_ratio = c.weighted_ratio, q.flicker_ratio = c.flicker_ratio;
    q.band_ratio = c.band_ratio;
    q.fovea_within_noise = c.fovea_within >= 1.0;
    r.points.push_back(q);
  }
  mark_pareto_front(r.points);
  return r;
}

}  // namespace foveal
