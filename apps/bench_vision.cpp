// apps/bench_vision.cpp — `foveal bench vision`: the second paper's Table 1 (per-stage times of
// one simulation step) on this machine.
#include "commands.h"
#include "foveal/io/outputs.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/util/stats.h"
#include "foveal/io/image_io.h"
#include "foveal/vision/simulate.h"
#include "foveal/vision/thin_lens.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>

namespace foveal::app {

namespace {

constexpr const char* kConferenceObj = "scenes/conference/conference.obj";

struct ImageError {
  double mean = 0, p95 = 0, psnr = 0;
};

// Absolute error over all channels of the sRGB-encoded images (what a viewer sees), and PSNR.
ImageError compare_images(const Image& a, const Image& b) {
  std::vector<double> e(a.pixels.size());
  double sum = 0, squares = 0;
  for (size_t i = 0; i < e.size(); ++i) {
    e[i] = std::abs(linear_to_srgb(a.pixels[i]) - linear_to_srgb(b.pixels[i]));
    sum += e[i];
    squares += e[i] * e[i];
  }
  std::sort(e.begin(), e.end());
  ImageError r;
  r.mean = sum / e.size();
  r.p95 = e[std::min(e.size() - 1, size_t(0.95 * e.size()))];
  const double mse = squares / e.size();
  r.psnr = mse > 0 ? 10 * std::log10(1.0 / mse) : INFINITY;
  return r;
}

}  // namespace

std::function<int()> add_bench_blur_command(CLI::App& bench) {
  auto* cmd = bench.add_subcommand("blur", "the variable blur against a distributed-ray-traced thin lens, for near, middle and far fixations");
  struct Options {
    std::string scene, size = "512x384", json, images;
    int samples = 256, threads = 0;
    double pupil = 3.5;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("--scene", o->scene, "scene (default: scenes/conference.json when ../shared/data has it, else builtin:box)");
  cmd->add_option("--size", o->size, "image size WxH")->capture_default_str();
  cmd->add_option("--lens-samples", o->samples, "lens samples per pixel of the reference")->capture_default_str();
  cmd->add_option("--pupil", o->pupil, "pupil diameter, mm")->capture_default_str();
  cmd->add_option("--threads", o->threads, "worker threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
  cmd->add_option("--json", o->json, "write the results as JSON");
  cmd->add_option("--images", o->images, "folder for the reference and approximation images (created)");
  return [o] {
    const ThreadScope threads(o->threads);
    std::string spec = o->scene;
    if (spec.empty()) spec = repository_scene("conference.json", kConferenceObj);
    if (spec.empty()) spec = "builtin:box";
    const Scene scene = load_scene(spec);
    const Tracer tracer(scene);
    const Camera camera = !scene.cameras.empty() ? scene.cameras.front() : default_camera(scene);
    const glm::ivec2 size = parse_size("--size", o->size);
    // Axial distances of the visible surfaces → near (5th percentile), middle (median), far (95th)
    const GBuffer g = trace_primary(tracer, scene, camera, size.x, size.y);
    const glm::vec3 forward = glm::normalize(camera.look - camera.eye);
    std::vector<double> depths;
    for (size_t i = 0; i < g.depth.size(); ++i)
      if (g.hit(i)) depths.push_back(g.depth[i] * glm::dot(g.view[i], forward) * scene.meters_per_unit);
    if (depths.empty()) fail("{}: the camera sees nothing", spec);
    std::sort(depths.begin(), depths.end());
    if (!o->images.empty()) std::filesystem::create_directories(o->images);
    fmt::print("foveal bench blur: {} ({} triangles), {}x{}, pupil {:g} mm, {} lens samples, {} threads\n", scene.source,
               tracer.triangles(), size.x, size.y, o->pupil, o->samples, threads.threads());
    // The pinhole image (how much blur there is to get right), the same for every focus
    ThinLensParams pinhole;
    pinhole.width = size.x;
    pinhole.height = size.y;
    pinhole.samples = 1;
    pinhole.pupil_diameter_mm = 1e-6;
    const Image sharp = thin_lens_reference(tracer, scene, camera, pinhole);
    if (!o->images.empty()) save_image(sharp, (std::filesystem::path(o->images) / "pinhole.png").string());
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& [name, q] : {std::pair{"near", 0.05}, std::pair{"middle", 0.5}, std::pair{"far", 0.95}}) {
      const double d = depths[size_t(q * (depths.size() - 1))];
      ThinLensParams p;
      p.width = size.x;
      p.height = size.y;
      p.samples = o->samples;
      p.pupil_diameter_mm = o->pupil;
      p.focus_vergence = 1.0 / d;
      const Image reference = thin_lens_reference(tracer, scene, camera, p);
      const Image approximation = thin_lens_approximation(tracer, scene, camera, p);
      const ImageError e = compare_images(approximation, reference), none = compare_images(sharp, reference);
      fmt::print("  {:<6} focus {:6.2f} m: approximation vs reference mean {:.4f}, p95 {:.4f}, PSNR {:.1f} dB   (pinhole vs reference: mean {:.4f}, PSNR {:.1f} dB)\n",
                 name, d, e.mean, e.p95, e.psnr, none.mean, none.psnr);
      rows.push_back({{"fixation", name}, {"focus_m", d}, {"mean_abs_error", e.mean}, {"p95_abs_error", e.p95}, {"psnr_db", e.psnr},
                      {"pinhole", {{"mean_abs_error", none.mean}, {"p95_abs_error", none.p95}, {"psnr_db", none.psnr}}}});
      if (!o->images.empty()) {
        save_image(reference, (std::filesystem::path(o->images) / fmt::format("{}-reference.png", name)).string());
        save_image(approximation, (std::filesystem::path(o->images) / fmt::format("{}-approximation.png", name)).string());
      }
    }
    if (!o->json.empty()) {
      write_json_file(o->json, {{"scene", scene.source}, {"size", o->size}, {"pupil_mm", o->pupil}, {"lens_samples", o->samples},
                                {"threads", threads.threads()}, {"rows", rows}});
    }
    return 0;
  };
}

std::function<int()> add_bench_vision_command(CLI::App& bench) {
  auto* cmd = bench.add_subcommand("vision", "the second paper's Table 1: milliseconds per stage of a simulation step");
  struct Options {
    std::vector<std::string> scenes, sizes{"1024x768", "1280x720"};
    std::string json, markdown, eye = "healthy";
    int steps = 20, threads = 0;
    uint64_t seed = 1;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("--scene", o->scenes, "scenes (default: scenes/conference.json when ../shared/data has it, and builtin:box)")->delimiter(',');
  cmd->add_option("--size", o->sizes, "sizes WxH")->delimiter(',')->capture_default_str();
  cmd->add_option("--steps", o->steps, "steps per case (median reported; the first is left out as warm-up)")
      ->capture_default_str()->check(CLI::Range(2, 10000));
  cmd->add_option("--eye", o->eye, "eye preset")->capture_default_str();
  cmd->add_option("--seed", o->seed, "seed of the saccades")->capture_default_str();
  cmd->add_option("--threads", o->threads, "worker threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
  cmd->add_option("--json", o->json, "write the table as JSON");
  cmd->add_option("--markdown", o->markdown, "write the table as Markdown");

  return [o] {
    const ThreadScope threads(o->threads);
    std::vector<std::string> scenes = o->scenes;
    if (scenes.empty()) {
      if (const std::string conference = repository_scene("conference.json", kConferenceObj); !conference.empty())
        scenes.push_back(conference);
      scenes.push_back("builtin:box");
    }
    const EyeParams eye = parse_eye_preset(o->eye);
    nlohmann::json rows = nlohmann::json::array();
    std::string md = fmt::format("| scene | size | trace ms | features ms | sharpness ms | blur ms | total ms | (features+sharpness+blur) / trace |\n"
                                 "|---|---|---:|---:|---:|---:|---:|---:|\n");
    fmt::print("foveal bench vision: {} steps per case (median of steps 2…), features every step, eye {}, {} threads\n", o->steps,
               o->eye, threads.threads());
    for (const std::string& spec : scenes) {
      const Scene scene = load_scene(spec);
      const Tracer tracer(scene);
      const Camera camera = !scene.cameras.empty() ? scene.cameras.front() : default_camera(scene);
      for (const std::string& size_text : o->sizes) {
        const glm::ivec2 size = parse_size("--size", size_text);
        SimulateParams p;
        p.width = size.x;
        p.height = size.y;
        p.eye = eye;
        p.seed = o->seed;
        p.features_every_step = true;  // the paper's timing: corners every step
        VisionSimulation sim(tracer, scene, p);
        std::vector<double> trace, features, sharpness, blur, total;
        for (int k = 0; k < o->steps; ++k) {
          const StepStats s = sim.step(camera);
          if (k == 0) continue;  // warm-up
          trace.push_back(s.trace_ms);
          features.push_back(s.features_ms);
          sharpness.push_back(s.sharpness_ms);
          blur.push_back(s.blur_ms);
          total.push_back(s.total_ms);
        }
        const double t = median(trace), f = median(features), sh = median(sharpness), b = median(blur),
                     all = median(total);
        const double ratio = t > 0 ? (f + sh + b) / t : 0;
        fmt::print("  {:<28} {:>9}  trace {:6.1f}  features {:6.1f}  sharpness {:6.1f}  blur {:6.1f}  total {:6.1f} ms  (rest/trace {:.2f})\n",
                   scene.source, size_text, t, f, sh, b, all, ratio);
        md += fmt::format("| {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.2f} |\n", scene.source, size_text, t, f, sh, b, all, ratio);
        rows.push_back({{"scene", scene.source}, {"triangles", tracer.triangles()}, {"size", size_text}, {"steps", o->steps - 1},
                        {"time_ms", {{"trace", t}, {"features", f}, {"sharpness", sh}, {"blur", b}, {"total", all}}},
                        {"non_tracing_over_trace", ratio}});
      }
    }
    if (!o->json.empty()) write_json_file(o->json, {{"threads", threads.threads()}, {"eye", o->eye}, {"rows", rows}});
    if (!o->markdown.empty()) write_text_file(o->markdown, md);
    return 0;
  };
}

}  // namespace foveal::app
