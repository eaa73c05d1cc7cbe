// foveal/experiments/sweep.h — the speed–quality trade-off of foveated AO: renders a grid of the
// model's parameters (γ, n_max, β) at several gaze points, times each frame against the full-frame
// reference of the same run, measures its error per eccentricity band against that reference and
// against the reference's own seed-to-seed noise, and marks the Pareto front (fastest for its
// error) of speed-up against the acuity-weighted error.
//
// Each (γ, n_max) is rendered with every method: the paper's, and the single-frame options of
// quality per ray (adaptive rays, denoising; temporal reuse needs a sequence, see sequence.h).
//
// β changes no ray (only how AO and the constant ambient term are mixed): the frames of one
// (γ, n_max, method) share their AO pass and are timed as one frame; each β is shaded and judged apart.
#pragma once

#include "foveal/quality/compare.h"
#include "foveal/experiments/sequence.h"
#include "foveal/render/render.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace foveal {

class Tracer;

struct QualitySweepParams {
  RenderParams render;      // size, display, ellipse, AO distance, ambient constant; γ, n_max, β, mode and gaze set per frame
  std::string camera_name;  // for the report only
  std::vector<std::pair<std::string, glm::dvec2>> gazes;
  std::vector<double> gammas{1, 1.5, 2, 3, 4};
  std::vector<int> max_rays{100, 200, 400};
  std::vector<double> betas{0.5, 1, 2};
  std::vector<ReuseConfig> methods{ReuseConfig{"paper", {}}};  // single-frame ones only (no temporal)
  int reference_rays = 400;                                    // the full-frame reference's rays per pixel
  uint64_t seed = 1;                                           // the foveated frames' seed; the references use seed + 1 and seed + 2
  int repeats = 1;                                             // timed frames per (γ, n_max) and for the reference (median)
  double saccade_deg = 5;                                      // flicker: the frame after a horizontal saccade of this many degrees
};

// One configuration at one gaze point.
struct QualityGazeResult {
  std::string gaze_label;
  glm::dvec2 gaze_px{0.0};
  double ms = 0;
  uint64_t ao_rays = 0;
  double weighted_rmse = 0, weighted_ratio = 0;  // acuity-weighted RMSE, and as a multiple of the reference's noise
  double weighted_noise_rmse = 0;                // the reference's own acuity-weighted seed-to-seed RMSE at this gaze
  // Flicker: the acuity-weighted RMSE (weights q² of this gaze) between this frame and the frame
  // rendered after a saccade of saccade_deg, where the full-frame reference does not change at all;
  // as a multiple of the reference's noise. Still-image errors miss it; the paper's blend exists to hide it.
  double flicker_rmse = 0, flicker_ratio = 0;
  std::vector<BandResult> bands;  // default_bands(), with the noise
  ErrorStats whole;
};

// One configuration over every gaze point.
struct QualityPoint {
  double gamma = 2, beta = 1;
  int max_rays = 400;
  std::string method = "paper";     // ReuseConfig::name
  double ms = 0;                    // mean frame time over the gaze points
  double speedup = 0;               // reference time / ms
  double ray_ratio = 0;             // reference AO rays / mean AO rays
  double weighted_ratio = 0;        // mean over gazes of the acuity-weighted error / reference noise
  double weighted_rmse = 0;         // mean over gazes
  double flicker_ratio = 0;         // mean over gazes
  std::vector<double> band_ratio;   // per band (default_bands order), mean error / noise over the gazes
  std::vector<double> band_rmse;    // per band, mean RMSE
  bool fovea_within_noise = false;  // the q(E) = 1 region within the reference's noise at every gaze
  bool pareto = false;              // no other point is at least as fast with at most its still error and flicker, and better in one
  std::vector<QualityGazeResult> per_gaze;
};

// The fewest rays any method that leaves the fovea unfiltered can cast at one gaze with the fovea
// within the reference's noise. An unbiased estimate of pixel i from n_i rays differs from the
// reference (N rays) by σ_i²/n_i + σ_i²/N in the mean square (σ_i² = V(1 − V)), the reference's
// seed-to-seed difference by 2σ_i²/N: the q(E) = 1 region is within noise when Σσ_i²/n_i ≤ Σσ_i²/N,
// and the fewest rays that do it are spread as n_i ∝ σ_i (Neyman's allocation), in all
// N·(Σσ_i)²/Σσ_i². σ_i is taken from the reference's visibility; shading weights are left out.
struct FoveaFloor {
  std::string gaze_label;
  uint64_t fovea_pixels = 0;     // q(E) = 1 pixels that hit the scene
  uint64_t partly_occluded = 0;  // … of which 0 < V < 1 in the reference
  double min_rays = 0;           // N·(Σσ)²/Σσ² over them
  double ray_ratio_bound = 0;    // reference AO rays / min_rays: no such method's ray ratio exceeds it
};

struct QualitySweepResult {
  std::string scene, camera;
  int width = 0, height = 0, reference_rays = 0, threads = 0;
  double saccade_deg = 0;
  size_t triangles = 0;
  double reference_ms = 0;  // median full-frame time
  uint64_t reference_ao_rays = 0;
  double reference_noise_weighted_rmse = 0;  // mean over gazes of the references' acuity-weighted seed-to-seed RMSE
  std::vector<std::string> band_names;
  std::vector<QualityPoint> points;      // in grid order: γ, then n_max, then method, then β
  std::vector<FoveaFloor> fovea_floors;  // per gaze point
};

// Run the sweep; `progress` receives a line per finished (γ, n_max).
QualitySweepResult run_quality_sweep(const Scene& scene, const Tracer& tracer, const Camera& camera, const QualitySweepParams& params,
                                     const std::function<void(const std::string&)>& progress = {});

// Mark each point's `pareto` flag: maximise speed-up, minimise the still error ratio and the flicker ratio.
void mark_pareto_front(std::vector<QualityPoint>& points);

// The fastest point whose fovea is within the reference's noise at every gaze, whose
// acuity-weighted error is at most `max_weighted_ratio` and whose flicker at most `max_flicker_ratio`
// times the reference's noise (the most accurate of equally fast ones); -1 if none.
int recommended_point(const std::vector<QualityPoint>& points, double max_weighted_ratio, double max_flicker_ratio);

nlohmann::json to_json(const QualitySweepResult& result);
// The table (one row per configuration, the Pareto front marked) as Markdown.
std::string to_markdown(const QualitySweepResult& result);
// Two panels, speed-up against the still error ratio and against the flicker ratio: every point
// (β by colour, method by marker), each panel's two-way front joined, the paper's method at the
// default configuration (`highlight`: γ, n_max, β) ringed; .png or .svg.
void write_pareto_plot(const QualitySweepResult& result, const std::string& path, double highlight_gamma, int highlight_max_rays,
                       double highlight_beta);
// A sequence's configurations as points of the plot (γ, n_max, β those of `foveation`; flicker
// the change between consecutive frames, saccade_deg 0; fovea within noise where it is in every frame).
QualitySweepResult sequence_points(const QualitySequenceResult& sequence, const FoveationParams& foveation);

}  // namespace foveal
