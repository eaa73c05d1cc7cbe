// foveal/experiments/sequence.cpp — see sequence.h.
#include "foveal/experiments/sequence.h"

#include "foveal/quality/compare.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/util/error.h"
#include "foveal/util/text.h"
#include "foveal/util/timer.h"

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <cmath>
#include <string_view>
#include <utility>

namespace foveal {

std::vector<ReuseConfig> default_sequence_configs() {
  std::vector<ReuseConfig> c(5);
  c[0].name = "paper";
  c[1].name = "adaptive+denoise";
  c[1].reuse.adaptive = c[1].reuse.denoise = true;
  c[2].name = "temporal";
  c[2].reuse.temporal = true;
  c[3].name = "temporal+adaptive";
  c[3].reuse.temporal = c[3].reuse.adaptive = true;
  c[4].name = "temporal+adaptive+denoise";
  c[4].reuse.temporal = c[4].reuse.adaptive = c[4].reuse.denoise = true;
  return c;
}

std::vector<ReuseConfig> parse_reuse_configs(const std::string& option, const std::string& list) {
  std::vector<ReuseConfig> configs;
  for (const std::string_view entry : text::split(list, ',')) {
    ReuseConfig c;
    bool paper = false;
    for (const std::string_view raw : text::split(entry, '+')) {
      const std::string_view word = text::trim(raw);
      bool* flag = word == "adaptive"   ? &c.reuse.adaptive
                   : word == "denoise"  ? &c.reuse.denoise
                   : word == "temporal" ? &c.reuse.temporal
                                        : nullptr;
      if (word == "paper") {
        if (paper) fail("{}: '{}' names paper twice", option, entry);
        paper = true;
      } else if (!flag) {
        fail("{}: unknown configuration '{}' in '{}' (paper, or adaptive, denoise, temporal joined by '+')", option, word, entry);
      } else if (*flag) {
        fail("{}: '{}' names {} twice", option, entry, word);
      } else {
        *flag = true;
      }
    }
    if (paper && c.reuse.any()) fail("{}: '{}' joins paper (no option) with options", option, entry);
    for (const auto& [on, word] : {std::pair{c.reuse.temporal, "temporal"}, {c.reuse.adaptive, "adaptive"}, {c.reuse.denoise, "denoise"}})
      if (on) {
        if (!c.name.empty()) c.name += '+';
        c.name += word;
      }
    if (c.name.empty()) c.name = "paper";
    for (const ReuseConfig& o : configs)
      if (o.name == c.name) fail("{}: {} is listed twice", option, c.name);
    configs.push_back(c);
  }
  return configs;
}

std::vector<Camera> orbit_path(const Camera& camera, double degrees, int frames) {
  std::vector<Camera> path;
  const glm::vec3 axis = glm::normalize(camera.up);
  for (int k = 0; k < frames; ++k) {
    const double a = frames > 1 ? glm::radians(degrees) * k / (frames - 1) : 0.0;
    Camera c = camera;
    const glm::vec3 r = camera.eye - camera.look;
    // Rodrigues' rotation of the eye about the vertical through the look point
    const float cs = static_cast<float>(std::cos(a)), sn = static_cast<float>(std::sin(a));
    c.eye = camera.look + r * cs + glm::cross(axis, r) * sn + axis * glm::dot(axis, r) * (1.0f - cs);
    path.push_back(c);
  }
  return path;
}

std::vector<glm::dvec2> fixation_path(glm::dvec2 centre, const RenderParams& p, int frames, int frames_per_fixation) {
  const double px_per_deg = pixels_per_degree(p.display) * p.width / p.display.res_x;
  const glm::dvec2 offsets[] = {{0, 0}, {1, 0.5}, {-1, 0}, {0.5, -1}};
  std::vector<glm::dvec2> gazes;
  for (int k = 0; k < frames; ++k) gazes.push_back(centre + px_per_deg * offsets[(k / std::max(1, frames_per_fixation)) % 4]);
  return gazes;
}

namespace {

// a + b − c per element (images of one size).
Image add_sub(const Image& a, const Image& b, const Image& c) {
  Image out = a;
  for (size_t i = 0; i < out.pixels.size(); ++i) out.pixels[i] = a.pixels[i] + b.pixels[i] - c.pixels[i];
  return out;
}

}  // namespace

QualitySequenceResult run_quality_sequence(const Scene& scene, FrameRenderer& renderer, const QualitySequenceParams& params,
                                           const std::function<void(const std::string&)>& progress) {
  auto say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  const int frames = static_cast<int>(params.cameras.size());
  if (frames < 2) fail("bench quality --sequence: needs at least 2 frames, got {}", frames);
  if (params.gazes.size() != params.cameras.size())
    fail("bench quality --sequence: {} gaze points for {} frames", params.gazes.size(), frames);
  if (params.configs.empty()) fail("bench quality --sequence: no configuration");
  validate(params.render);
  for (const ReuseConfig& c : params.configs) {
    RenderParams check = params.render;
    check.reuse = c.reuse;
    check.reuse.target_rays = params.reference_rays;
    validate(check);
  }
  QualitySequenceResult result;
  result.scene = scene.source;
  result.width = params.render.width;
  result.height = params.render.height;
  result.frames = frames;
  result.gazes = params.gazes;
  result.reference_rays = params.reference_rays;
  result.threads = static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  // Every frame on the renderer's device, with the history it keeps
  result.device = renderer.device() == ComputeDevice::cuda ? renderer.describe() : "cpu";
  const auto render = [&](const Camera& camera, const RenderParams& p) {
    FrameOptions options;
    options.outputs = FrameOutputs::colour_only();
    return renderer.render(camera, p, options);
  };
  for (const Band& b : default_bands()) result.band_names.push_back(b.name);

  // The references at every frame (and their noise), rendered first: the same for every configuration
  RenderParams full = params.render;
  full.mode = RenderMode::full;
  full.reuse = {};
  full.foveation.max_rays = params.reference_rays;
  full.foveation.min_rays = std::min(full.foveation.min_rays, params.reference_rays);
  std::vector<Image> references;
  std::vector<ReferenceNoise> noises;
  uint64_t reference_rays = 0;
  for (int k = 0; k < frames; ++k) {
    full.seed = params.seed + 1;
    const Timer clock;
    Frame r = render(params.cameras[k], full);
    result.reference_ms += clock.ms() / frames;
    reference_rays += r.stats.ao_rays;
    full.seed = params.seed + 2;
    noises.push_back(reference_noise(render(params.cameras[k], full).color, r.color));
    references.push_back(std::move(r.color));
    say(fmt::format("reference frame {}/{}", k + 1, frames));
  }
  say(fmt::format("reference: {:.0f} ms a frame", result.reference_ms));

  const size_t bands = result.band_names.size();
  for (const ReuseConfig& config : params.configs) {
    SequenceConfigResult r;
    r.name = config.name;
    r.reuse = config.reuse;
    r.band_ratio.assign(bands, 0.0);
    std::vector<int> band_frames(bands, 0);
    renderer.reset_history();
    Image previous;
    uint64_t rays = 0;
    for (int k = 0; k < frames; ++k) {
      RenderParams p = params.render;
      p.mode = RenderMode::foveated;
      p.gaze_px = params.gazes[k];
      p.reuse = config.reuse;
      p.reuse.target_rays = params.reference_rays;  // τ(E) from the noise of the reference judged against
      p.seed = params.seed;
      const Timer clock;
      Frame f = render(params.cameras[k], p);
      r.ms += clock.ms() / frames;
      rays += f.stats.ao_rays;
      const Comparison c = compare_images(f.color, references[k], noises[k], p.display, params.gazes[k], p.foveation);
      r.frame_weighted_ratio.push_back(c.weighted_ratio());
      r.weighted_ratio += c.weighted_ratio() / frames;
      for (size_t b = 0; b < bands; ++b) {
        const BandResult& band = c.bands[b];
        if (band.error.pixels == 0) continue;
        r.band_ratio[b] += band.noise_ratio;
        ++band_frames[b];
        if (band.band.foveal_region) {
          r.fovea_ratio += band.noise_ratio / frames;
          r.fovea_within += (band.within_noise ? 1.0 : 0.0) / frames;
        }
      }
      // Flicker: the change of the error from the last frame, (I_k − R_k) − (I_{k−1} − R_{k−1})
      if (k > 0 && c.weighted_noise_rmse > 0)
        r.flicker_ratio += acuity_weighted_rmse(add_sub(f.color, references[k - 1], references[k]), previous, c.quality) /
                           c.weighted_noise_rmse / (frames - 1);
      previous = std::move(f.color);
    }
    for (size_t b = 0; b < bands; ++b) r.band_ratio[b] = band_frames[b] ? r.band_ratio[b] / band_frames[b] : std::nan("");
    r.speedup = r.ms > 0 ? result.reference_ms / r.ms : 0.0;
    r.ray_ratio = rays > 0 ? static_cast<double>(reference_rays) / static_cast<double>(rays) : INFINITY;
    say(fmt::format("{}: {:.0f} ms a frame ({:.2f}x), error {:.2f}x, flicker {:.2f}x, fovea {:.2f}x noise", r.name, r.ms, r.speedup,
                    r.weighted_ratio, r.flicker_ratio, r.fovea_ratio));
    result.configs.push_back(std::move(r));
  }
  return result;
}

nlohmann::json to_json(const QualitySequenceResult& r) {
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json j = {{"scene", r.scene},
                      {"width", r.width},
                      {"height", r.height},
                      {"frames", r.frames},
                      {"threads", r.threads},
                      {"device", r.device},
                      {"reference_rays", r.reference_rays},
                      {"reference_ms", r.reference_ms},
                      {"bands", r.band_names},
                      {"configs", nlohmann::json::array()},
                      {"gazes", nlohmann::json::array()}};
  for (const glm::dvec2& g : r.gazes) j["gazes"].push_back({g.x, g.y});
  for (const SequenceConfigResult& c : r.configs) {
    nlohmann::json b = nlohmann::json::array();
    for (double v : c.band_ratio) b.push_back(number(v));
    j["configs"].push_back({{"name", c.name},
                            {"adaptive", c.reuse.adaptive},
                            {"denoise", c.reuse.denoise},
                            {"temporal", c.reuse.temporal},
                            {"ms", c.ms},
                            {"speedup", c.speedup},
                            {"ray_ratio", number(c.ray_ratio)},
                            {"weighted_ratio", c.weighted_ratio},
                            {"flicker_ratio", c.flicker_ratio},
                            {"fovea_ratio", c.fovea_ratio},
                            {"fovea_within_fraction", c.fovea_within},
                            {"band_ratio", b},
                            {"frame_weighted_ratio", c.frame_weighted_ratio}});
  }
  return j;
}

std::string to_markdown(const QualitySequenceResult& r) {
  std::string out = fmt::format(
      "{}, {}x{}, {} frames; reference: full frame with {} rays per pixel at every frame's camera, {:.0f} ms a frame ({}). "
      "Speed-up = reference time / the configuration's mean frame time; errors are acuity-weighted RMSE against each frame's "
      "reference in units of that reference's own seed-to-seed noise (mean over frames); flicker = the acuity-weighted change of the "
      "error between consecutive frames, same unit.\n\n",
      r.scene, r.width, r.height, r.frames, r.reference_rays, r.reference_ms,
      r.device == "cpu" || r.device.empty() ? fmt::format("{} threads", r.threads) : "GPU: " + r.device);
  out += "| configuration | ms | speed-up | AO ray ratio | acuity-weighted × noise | flicker × noise | q(E) = 1 × noise | frames within |";
  std::string rule = "|---|---:|---:|---:|---:|---:|---:|---:|";
  for (const std::string& b : r.band_names)
    if (b != "q=1") out += fmt::format(" {}° |", b), rule += "---:|";
  out += "\n" + rule + "\n";
  for (const SequenceConfigResult& c : r.configs) {
    out += fmt::format("| {} | {:.0f} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {:.0f} % |", c.name, c.ms, c.speedup, c.ray_ratio,
                       c.weighted_ratio, c.flicker_ratio, c.fovea_ratio, 100 * c.fovea_within);
    for (size_t b = 0; b < r.band_names.size(); ++b)
      if (r.band_names[b] != "q=1") out += std::isfinite(c.band_ratio[b]) ? fmt::format(" {:.2f} |", c.band_ratio[b]) : " – |";
    out += "\n";
  }
  return out;
}

}  // namespace foveal
