// The speed–quality sweep: a configuration that casts the reference's rays everywhere and blends
// no constant ambient term is indistinguishable from the reference's own noise in every band; the
// ray budget falls as γ grows; the Pareto front is exactly the non-dominated set; the
// recommendation follows its definition; the acuity-weighted RMSE is the weighted mean it claims.
#include "foveal/experiments/sweep.h"
#include "foveal/trace/tracer.h"
#include "foveal/util/error.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

namespace foveal {
namespace {

QualityPoint point(double speedup, double ratio, bool fovea = true, double flicker = 0) {
  QualityPoint p;
  p.speedup = speedup;
  p.weighted_ratio = ratio;
  p.flicker_ratio = flicker;
  p.fovea_within_noise = fovea;
  return p;
}

TEST(QualitySweep, ParetoFrontIsTheNonDominatedSet) {
  std::vector<QualityPoint> pts = {point(1, 1), point(2, 3), point(2, 2), point(3, 5), point(1.5, 4), point(3, 5)};
  mark_pareto_front(pts);
  EXPECT_TRUE(pts[0].pareto);   // the most accurate
  EXPECT_FALSE(pts[1].pareto);  // as fast as pts[2] with more error
  EXPECT_TRUE(pts[2].pareto);
  EXPECT_TRUE(pts[3].pareto);   // the fastest (its twin equal, neither dominates the other)
  EXPECT_FALSE(pts[4].pareto);  // slower and worse than pts[2]
  EXPECT_TRUE(pts[5].pareto);
  // A third objective: less flicker keeps a slower, less accurate point on the front
  pts.push_back(point(1.5, 4, true, -1));
  mark_pareto_front(pts);
  EXPECT_TRUE(pts.back().pareto);
  EXPECT_FALSE(pts[4].pareto);
  // The recommendation: fastest within the bounds and with the fovea within noise
  EXPECT_EQ(recommended_point(pts, 2.5, 1), 2);
  EXPECT_EQ(recommended_point(pts, 2.5, -0.5), -1);  // only the flicker-free point passes, and its error is too large
  EXPECT_EQ(recommended_point(pts, 4, -0.5), 6);
  pts[2].fovea_within_noise = false;
  EXPECT_EQ(recommended_point(pts, 2.5, 1), 0);
  EXPECT_EQ(recommended_point(pts, 0.5, 1), -1);
}

// A 160×100 sweep of the built-in box against a reference of `reference_rays` rays.
QualitySweepParams small_sweep(int reference_rays) {
  QualitySweepParams p;
  p.render.width = 160;
  p.render.height = 100;
  p.reference_rays = reference_rays;
  return p;
}

TEST(QualitySweep, ReferenceLikeConfigurationIsWithinNoiseEverywhere) {
  const Scene scene = load_scene("builtin:box");
  const Tracer tracer(scene);
  const Camera camera = default_camera(scene);
  QualitySweepParams p = small_sweep(32);
  p.gazes = {{"centre", {80, 50}}, {"left", {20, 60}}};
  // γ → 0: every pixel gets the reference's 32 rays; β = 0: AO everywhere, no constant term.
  // γ = 2, β = 1: the papers' blend; γ = 4: fewer rays still.
  p.gammas = {0.001, 2, 4};
  p.max_rays = {32};
  p.betas = {0, 1};
  const QualitySweepResult r = run_quality_sweep(scene, tracer, camera, p);
  ASSERT_EQ(r.points.size(), 6u);
  ASSERT_EQ(r.band_names.size(), default_bands().size());
  const QualityPoint& like_reference = r.points[0];
  EXPECT_EQ(like_reference.gamma, 0.001);
  EXPECT_EQ(like_reference.beta, 0.0);
  EXPECT_NEAR(like_reference.ray_ratio, 1.0, 0.01);
  EXPECT_TRUE(like_reference.fovea_within_noise);
  for (const QualityGazeResult& g : like_reference.per_gaze)
    for (const BandResult& b : g.bands)
      if (b.error.pixels > 200) EXPECT_TRUE(b.within_noise) << g.gaze_label << " " << b.band.name << " ×" << b.noise_ratio;
  EXPECT_NEAR(like_reference.weighted_ratio, 1.0, 0.15);
  // Nearly the reference's rays at every pixel, whatever the gaze: next to no flicker after a
  // saccade; the defaults' budget changes with the gaze, so their frames change
  EXPECT_LT(like_reference.flicker_ratio, 0.2);
  EXPECT_GT(r.points[3].flicker_ratio, like_reference.flicker_ratio);
  // β changes no ray: the two βs of one γ have the same frame time and ray ratio
  for (size_t k = 0; k < r.points.size(); k += 2) {
    EXPECT_EQ(r.points[k].ms, r.points[k + 1].ms);
    EXPECT_EQ(r.points[k].ray_ratio, r.points[k + 1].ray_ratio);
  }
  // Fewer rays as γ grows; the fovea keeps the reference's rays, so stays within noise
  EXPECT_LT(r.points[0].ray_ratio, r.points[2].ray_ratio);
  EXPECT_LT(r.points[2].ray_ratio, r.points[4].ray_ratio);
  EXPECT_TRUE(r.points[2].fovea_within_noise);
  // Speed-up is the reference's time over the mean frame time
  for (const QualityPoint& q : r.points) {
    double ms = 0;
    for (const auto& g : q.per_gaze) ms += g.ms / q.per_gaze.size();
    EXPECT_NEAR(q.speedup, r.reference_ms / ms, 1e-9 * q.speedup);
  }
  // The front: no point on it is dominated, every point off it is
  for (const QualityPoint& a : r.points) {
    bool dominated = false;
    for (const QualityPoint& b : r.points)
      dominated |=
          b.speedup >= a.speedup && b.weighted_ratio <= a.weighted_ratio && (b.speedup > a.speedup || b.weighted_ratio < a.weighted_ratio);
    EXPECT_EQ(a.pareto, !dominated);
  }
}

TEST(QualitySweep, MethodsAreSweptLikeParametersAndTheFoveaFloorBoundsTheRays) {
  const Scene scene = load_scene("builtin:box");
  const Tracer tracer(scene);
  const Camera camera = default_camera(scene);
  QualitySweepParams p = small_sweep(64);
  p.gazes = {{"centre", {80, 50}}};
  p.gammas = {2};
  p.max_rays = {64};
  p.betas = {0, 1};
  p.methods = parse_reuse_configs("--configs", "paper,adaptive,adaptive+denoise");
  const QualitySweepResult r = run_quality_sweep(scene, tracer, camera, p);
  // γ, n_max, then method, then β
  ASSERT_EQ(r.points.size(), 6u);
  const char* names[] = {"paper", "paper", "adaptive", "adaptive", "adaptive+denoise", "adaptive+denoise"};
  for (size_t k = 0; k < r.points.size(); ++k) {
    EXPECT_EQ(r.points[k].method, names[k]);
    EXPECT_EQ(r.points[k].beta, k % 2 ? 1.0 : 0.0);
  }
  // Adaptive rays stop early where the estimate is certain: fewer rays than the paper's budget;
  // the filter casts none, so adaptive+denoise casts what adaptive casts
  EXPECT_GT(r.points[2].ray_ratio, r.points[0].ray_ratio);
  EXPECT_EQ(r.points[4].ray_ratio, r.points[2].ray_ratio);
  // ... and pools rays where a pixel is noisier than its eccentricity allows: less error than adaptive alone
  EXPECT_LT(r.points[4].weighted_ratio, r.points[2].weighted_ratio);
  // The floor: N·(Σσ)²/Σσ² lies between N (one noisy pixel's worth) and N per partly occluded pixel
  // (Cauchy–Schwarz), and the paper's frame, which casts N at every q = 1 pixel, is no faster in rays
  ASSERT_EQ(r.fovea_floors.size(), 1u);
  const FoveaFloor& f = r.fovea_floors[0];
  EXPECT_GT(f.fovea_pixels, 100u);
  EXPECT_GT(f.partly_occluded, 0u);
  EXPECT_LE(f.partly_occluded, f.fovea_pixels);
  EXPECT_GE(f.min_rays, p.reference_rays);
  EXPECT_LE(f.min_rays, double(p.reference_rays) * f.partly_occluded * (1 + 1e-9));
  EXPECT_NEAR(f.ray_ratio_bound, double(r.reference_ao_rays) / f.min_rays, 1e-9 * f.ray_ratio_bound);
  EXPECT_LE(r.points[0].ray_ratio, f.ray_ratio_bound);
  // The table names the methods and the floor; the JSON carries both
  const std::string md = to_markdown(r);
  EXPECT_NE(md.find("| adaptive+denoise | 2 | 64 | 1 |"), std::string::npos);
  EXPECT_NE(md.find(fmt::format("at most {:.2f} at centre", f.ray_ratio_bound)), std::string::npos);
  const auto j = to_json(r);
  EXPECT_EQ(j["points"][4]["method"], "adaptive+denoise");
  EXPECT_EQ(j["fovea_floors"][0]["partly_occluded"], f.partly_occluded);
  // Temporal reuse has no earlier frame to reuse in a single frame
  p.methods = parse_reuse_configs("--configs", "temporal");
  EXPECT_THROW(run_quality_sweep(scene, tracer, camera, p), Error);
  // An open plane: nothing occluded in the fovea, no floor
  const Scene plane = load_scene("builtin:plane");
  const Tracer plane_tracer(plane);
  p.methods = parse_reuse_configs("--configs", "paper");
  p.betas = {0};
  const QualitySweepResult open = run_quality_sweep(plane, plane_tracer, default_camera(plane), p);
  EXPECT_EQ(open.fovea_floors[0].partly_occluded, 0u);
  EXPECT_TRUE(std::isinf(open.fovea_floors[0].ray_ratio_bound));
}

TEST(QualitySweep, BadGridIsRefused) {
  const Scene scene = load_scene("builtin:plane");
  const Tracer tracer(scene);
  QualitySweepParams p;
  p.render.width = 16;
  p.render.height = 16;
  p.gazes = {{"centre", {8, 8}}};
  p.gammas = {0};
  EXPECT_THROW(run_quality_sweep(scene, tracer, default_camera(scene), p), Error);
  p.gammas = {2};
  p.betas = {};
  EXPECT_THROW(run_quality_sweep(scene, tracer, default_camera(scene), p), Error);
  p.betas = {1};
  p.gazes.clear();
  EXPECT_THROW(run_quality_sweep(scene, tracer, default_camera(scene), p), Error);
}

TEST(QualitySweep, AcuityWeightedRmseIsTheWeightedMean) {
  const int w = 120, h = 80;
  Image a(w, h, 3), b(w, h, 3);
  for (float& v : a.pixels) v = 0.5f;
  b = a;
  const Display display;  // the paper's lab display
  const glm::dvec2 gaze(30, 40);
  FoveationParams fp;
  // A uniform error δ: every weighting gives δ
  for (float& v : b.pixels) v += 0.01f;
  Comparison c = compare_images(a, b, nullptr, display, gaze, fp);
  EXPECT_NEAR(c.weighted_rmse, 0.01, 1e-6);
  // Error only on one pixel far from the gaze and one inside the fovea: the weights are q² there
  b = a;
  const int far_x = w - 1, far_y = h - 1, near_x = 30, near_y = 40;
  for (int ch = 0; ch < 3; ++ch) b.at(far_x, far_y, ch) += 0.1f, b.at(near_x, near_y, ch) += 0.1f;
  c = compare_images(a, b, nullptr, display, gaze, fp);
  double sum_w = 0;
  for (float q : c.quality) sum_w += double(q) * q;
  const double q_far = c.quality[size_t(far_y) * w + far_x], q_near = c.quality[size_t(near_y) * w + near_x];
  EXPECT_EQ(q_near, 1.0);
  EXPECT_LT(q_far, 1.0);
  const double d = double(0.5f + 0.1f) - 0.5;
  EXPECT_NEAR(c.weighted_rmse, std::sqrt((q_far * q_far + 1.0) * d * d / sum_w), 1e-9);
  // The stand-alone weighted RMSE (the sweep's flicker) is the comparison's
  EXPECT_DOUBLE_EQ(acuity_weighted_rmse(b, a, c.quality), c.weighted_rmse);
}

TEST(QualitySweep, PrecomputedReferenceNoiseGivesTheSameComparison) {
  // The sweep computes the reference's noise maps once; every figure must equal the one-call comparison
  const int w = 90, h = 60;
  Image a(w, h, 3), b(w, h, 3), b2(w, h, 3);
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    a.pixels[i] = 0.5f + 0.3f * std::sin(0.37f * i);
    b.pixels[i] = 0.5f + 0.3f * std::sin(0.37f * i + 0.05f);
    b2.pixels[i] = 0.5f + 0.3f * std::sin(0.37f * i - 0.04f);
  }
  const Display display;
  const FoveationParams fp;
  const Comparison once = compare_images(a, b, &b2, display, {20, 30}, fp);
  const ReferenceNoise noise = reference_noise(b2, b);
  for (const glm::dvec2 gaze : {glm::dvec2(20, 30), glm::dvec2(80, 10)}) {
    const Comparison direct = compare_images(a, b, &b2, display, gaze, fp);
    const Comparison cached = compare_images(a, b, noise, display, gaze, fp);
    EXPECT_EQ(cached.weighted_noise_rmse, direct.weighted_noise_rmse);
    EXPECT_EQ(cached.whole_noise->rmse, direct.whole_noise->rmse);
    EXPECT_EQ(cached.whole_noise->ssim, direct.whole_noise->ssim);
    for (size_t k = 0; k < direct.bands.size(); ++k) {
      EXPECT_EQ(cached.bands[k].noise_ratio, direct.bands[k].noise_ratio) << k;
      EXPECT_EQ(cached.bands[k].within_noise, direct.bands[k].within_noise) << k;
    }
  }
  EXPECT_GT(once.weighted_noise_rmse, 0.0);
  Image small(10, 10, 3);
  EXPECT_THROW(compare_images(small, small, noise, display, {5, 5}, fp), Error);  // maps of another size
}

}  // namespace
}  // namespace foveal
