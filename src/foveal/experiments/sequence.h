// foveal/experiments/sequence.h — quality per ray over a sequence: each configuration of the reuse
// options (adaptive rays, denoising, temporal accumulation) rendered along a camera path with a
// moving gaze, every frame judged against the full-frame reference rendered at the same camera in
// the same run, in units of that reference's own seed-to-seed noise.
#pragma once

#include "foveal/render/render.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace foveal {

class FrameRenderer;

// One way of spending the AO rays: the paper's method, or the reuse options on top of it.
struct ReuseConfig {
  std::string name;  // "paper", or its options joined by '+' in the order temporal, adaptive, denoise
  AoReuseParams reuse;
};
// paper, adaptive+denoise, temporal, temporal+adaptive, temporal+adaptive+denoise.
std::vector<ReuseConfig> default_sequence_configs();
// A comma-separated list of configurations, each "paper" or options joined by '+' (adaptive,
// denoise, temporal, in any order; the name is given back in the canonical order). Throws Error
// naming `option` and the bad entry.
std::vector<ReuseConfig> parse_reuse_configs(const std::string& option, const std::string& list);

struct QualitySequenceParams {
  RenderParams render;            // size, display, model; gaze and reuse set per frame and configuration
  std::vector<Camera> cameras;    // one per frame
  std::vector<glm::dvec2> gazes;  // one per frame, render pixels
  std::vector<ReuseConfig> configs = default_sequence_configs();
  int reference_rays = 400;
  uint64_t seed = 1;  // the configurations' seed; references seed + 1 and seed + 2
};

struct SequenceConfigResult {
  std::string name;
  AoReuseParams reuse;
  double ms = 0;                             // mean frame time
  double speedup = 0;                        // reference mean frame time / ms
  double ray_ratio = 0;                      // reference AO rays / this configuration's
  double weighted_ratio = 0;                 // mean over frames of the acuity-weighted error / the reference's noise
  double flicker_ratio = 0;                  // mean over frame pairs of the acuity-weighted change of the error / noise
  double fovea_ratio = 0;                    // mean over frames of the q(E) = 1 region's error / noise
  double fovea_within = 0;                   // fraction of frames whose q(E) = 1 region is within the reference's noise
  std::vector<double> band_ratio;            // per band (default_bands), mean over frames
  std::vector<double> frame_weighted_ratio;  // per frame
};

struct QualitySequenceResult {
  std::string scene;
  int width = 0, height = 0, frames = 0, reference_rays = 0, threads = 0;
  std::string device;             // "cpu", or the GPU's description
  double reference_ms = 0;        // mean full-frame time
  std::vector<glm::dvec2> gazes;  // per frame, render pixels
  std::vector<std::string> band_names;
  std::vector<SequenceConfigResult> configs;
};

// A camera orbiting `camera`'s look point about the vertical by `degrees` over `frames` frames.
std::vector<Camera> orbit_path(const Camera& camera, double degrees, int frames);
// A gaze that fixates around `centre` (render pixels): a new fixation every `frames_per_fixation`
// frames, the offsets cycling through (0, 0), (1, 0.5), (−1, 0), (0.5, −1) degrees.
std::vector<glm::dvec2> fixation_path(glm::dvec2 centre, const RenderParams& params, int frames, int frames_per_fixation);

// Every frame, the references too, rendered by `renderer` (any device; its history is reset for
// each configuration); `scene` is the one it renders (its name goes into the result).
QualitySequenceResult run_quality_sequence(const Scene& scene, FrameRenderer& renderer, const QualitySequenceParams& params,
                                           const std::function<void(const std::string&)>& progress = {});

nlohmann::json to_json(const QualitySequenceResult& result);
std::string to_markdown(const QualitySequenceResult& result);

}  // namespace foveal
