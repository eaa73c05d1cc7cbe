// apps/bench_vision.cpp — `foveal bench vision`: the second paper's Table 1 (per-stage times of
// one simulation step) on this machine.
#include "commands.h"
#include "foveal/cuda/gpu.h"
#include "foveal/impair/profile.h"
#include "foveal/render/outputs.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/util/stats.h"
#include "foveal/io/image_io.h"
#include "foveal/render/pixel.h"
#include "foveal/trace/tracer.h"
#include "foveal/vision/features.h"
#include "foveal/impair/profile.h"
#include "foveal/vision/simulate.h"
#include "foveal/vision/thin_lens.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <memory>
#include <span>
#include <tuple>

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
  auto* cmd =
      bench.add_subcommand("blur", "the variable blur against a distributed-ray-traced thin lens, for near, middle and far fixations");
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
  cmd->add_option("--json", o->json, "write the results as JSON")->check(output_file());
  cmd->add_option("--images", o->images, "folder for the reference and approximation images (created)");
  return [o] {
    const ThreadScope threads(o->threads);
    std::string spec = o->scene;
    if (spec.empty()) spec = repository_scene("conference.json", kConferenceObj);
    if (spec.empty()) spec = "builtin:box";
    const Scene scene = load_scene(spec);
    const Tracer tracer(scene);
    const Camera camera = first_camera(scene);
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
      fmt::print(
          "  {:<6} focus {:6.2f} m: approximation vs reference mean {:.4f}, p95 {:.4f}, PSNR {:.1f} dB   (pinhole vs reference: mean "
          "{:.4f}, PSNR {:.1f} dB)\n",
          name, d, e.mean, e.p95, e.psnr, none.mean, none.psnr);
      rows.push_back({{"fixation", name},
                      {"focus_m", d},
                      {"mean_abs_error", e.mean},
                      {"p95_abs_error", e.p95},
                      {"psnr_db", e.psnr},
                      {"pinhole", {{"mean_abs_error", none.mean}, {"p95_abs_error", none.p95}, {"psnr_db", none.psnr}}}});
      if (!o->images.empty()) {
        save_image(reference, (std::filesystem::path(o->images) / fmt::format("{}-reference.png", name)).string());
        save_image(approximation, (std::filesystem::path(o->images) / fmt::format("{}-approximation.png", name)).string());
      }
    }
    if (!o->json.empty()) {
      write_json_file(o->json, {{"scene", scene.source},
                                {"size", o->size},
                                {"pupil_mm", o->pupil},
                                {"lens_samples", o->samples},
                                {"threads", threads.threads()},
                                {"rows", rows}});
    }
    return 0;
  };
}

namespace {

// Medians over the steps after the first (warm-up) of one case on one device.
struct StageTimes {
  double trace = 0, features = 0, sharpness = 0, blur = 0, total = 0;
  ImpairTimes impair;  // the impairment passes (media, retina, colour; on the CPU)
};

// Collects one device's step timings and gives their medians.
struct StageSeries {
  std::vector<double> trace, features, sharpness, blur, total, media, retina, colour, impair;
  void add(const StepStats& s) {
    media.push_back(s.impair.media_ms);
    retina.push_back(s.impair.field_ms);
    colour.push_back(s.impair.colour_ms);
    impair.push_back(s.impair.total_ms);
    trace.push_back(s.trace_ms);
    features.push_back(s.features_ms);
    sharpness.push_back(s.sharpness_ms);
    blur.push_back(s.blur_ms);
    total.push_back(s.total_ms);
  }
  StageTimes medians() const {
    return {median(trace), median(features), median(sharpness),
            median(blur),  median(total),    ImpairTimes{median(media), median(retina), median(colour), median(impair)}};
  }
};

// How far two devices' free-running simulations of one case agree. Each device draws its own
// saccades from the same seed, so the chains stay the same while the corners do; the first step
// whose corners differ says why (how many of the FAST image's grey pixels differ).
struct Agreement {
  int steps = 0;
  int same_fixations = 0;           // leading steps whose fixations are identical
  int first_corner_difference = 0;  // the first step whose corners differ (0: none did)
  size_t grey_px_differing = 0;     // … and at that step: grey pixels that differ, of grey_px
  size_t grey_px = 0;
  size_t corners_differing = 0;  // corners of one device only (of corners_total on the GPU)
  size_t corners_total = 0;
  double perceived_mean_abs_diff = 0;  // the largest per-step mean while the fixations are identical
};

bool same_corners(const std::vector<Corner>& a, const std::vector<Corner>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](const Corner& l, const Corner& r) { return l.px == r.px && l.score == r.score; });
}

// Corners found by one device and not by the other.
size_t corners_of_one(const std::vector<Corner>& a, const std::vector<Corner>& b) {
  auto key = [](const Corner& c) { return std::tuple(c.px.y, c.px.x, c.score); };
  std::vector<std::tuple<float, float, float>> ka, kb, only;
  for (const Corner& c : a) ka.push_back(key(c));
  for (const Corner& c : b) kb.push_back(key(c));
  std::sort(ka.begin(), ka.end());
  std::sort(kb.begin(), kb.end());
  std::set_symmetric_difference(ka.begin(), ka.end(), kb.begin(), kb.end(), std::back_inserter(only));
  return only.size();
}

double mean_abs_diff(const Image& a, const Image& b) {
  double diff = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) diff += std::abs(a.pixels[i] - b.pixels[i]);
  return diff / double(std::max<size_t>(1, a.pixels.size()));
}

// The primary rays of a w×h image in 16×8 tiles, the order in which the GPU's trace pass groups
// them (and coherent runs for Embree's streams): the rays of the raw-tracing baselines.
std::vector<Ray> primary_rays_in_tiles(const Camera& camera, int w, int h) {
  const CameraRays ray(camera, w, h);
  std::vector<Ray> rays;
  rays.reserve(static_cast<size_t>(w) * h);
  for (int ty = 0; ty < h; ty += 8)
    for (int tx = 0; tx < w; tx += 16)
      for (int y = ty; y < std::min(h, ty + 8); ++y)
        for (int x = tx; x < std::min(w, tx + 16); ++x) rays.push_back(ray(x + 0.5, y + 0.5));
  return rays;
}

// Raw Embree closest-hit rays per second on `rays`: the median of three runs after a warm-up.
double raw_embree_rate(const Tracer& tracer, std::span<const Ray> rays) {
  measure_raw_intersection(tracer, rays);
  std::vector<double> rates;
  for (int k = 0; k < 3; ++k) rates.push_back(measure_raw_intersection(tracer, rays).rays_per_second);
  return median(rates);
}

// One case: the steps of `p` (on its device); with `compare`, the same case on the CPU step for
// step beside it, for the ratio and the agreement.
struct VisionCase {
  StageTimes times, cpu;
  Agreement agreement;
};

VisionCase run_vision_case(const Tracer& tracer, const Scene& scene, const Camera& camera, const SimulateParams& p, int steps,
                           bool compare) {
  VisionSimulation sim(tracer, scene, p);
  std::unique_ptr<VisionSimulation> cpu;
  if (compare) {
    SimulateParams q = p;
    q.cuda = false;
    cpu = std::make_unique<VisionSimulation>(tracer, scene, q);
  }
  StageSeries own, other;
  VisionCase c;
  bool fixations_same = true;
  for (int k = 0; k < steps; ++k) {
    const StepStats s = sim.step(camera);
    if (k > 0) own.add(s);  // the first is the warm-up
    if (!cpu) continue;
    const StepStats t = cpu->step(camera);
    if (k > 0) other.add(t);
    Agreement& g = c.agreement;
    g.steps = k + 1;
    if (!fixations_same) continue;  // the chains have parted: nothing more to compare
    // This step's fixation is drawn among this step's corners: compare them first
    if (g.first_corner_difference == 0 && !same_corners(sim.corners(), cpu->corners())) {
      g.first_corner_difference = k + 1;
      const std::vector<uint8_t> ga = grey_8bit(sim.color()), gb = grey_8bit(cpu->color());
      g.grey_px = ga.size();
      for (size_t i = 0; i < ga.size(); ++i) g.grey_px_differing += ga[i] != gb[i];
      g.corners_differing = corners_of_one(sim.corners(), cpu->corners());
      g.corners_total = sim.corners().size();
    }
    fixations_same = s.focus_px == t.focus_px;
    if (!fixations_same) continue;
    ++g.same_fixations;
    g.perceived_mean_abs_diff = std::max(g.perceived_mean_abs_diff, mean_abs_diff(sim.perceived(), cpu->perceived()));
  }
  c.times = own.medians();
  if (cpu) c.cpu = other.medians();
  return c;
}

// The command's options as typed.
struct BenchVisionOptions {
  std::vector<std::string> scenes, sizes{"1024x768", "1280x720"};
  std::string json, markdown, eye = "healthy", device = "auto";
  std::optional<double> pupil;  // not given: the eye's (a profile's pupil_mm, else 3.5)
  std::string impairments = "cataract:0.5+field:arcuate:20+metamorphopsia:0.3+cvd:deutan:0.6";
  int steps = 20, threads = 0;
  uint64_t seed = 1;
};

// One row of the table: a scene at a size, on the chosen device (and on the CPU beside the GPU).
struct VisionRow {
  std::string scene, size;
  size_t triangles = 0, rays = 0;  // the primary rays of a step
  VisionCase vc;
  double raw = 0, raw_cpu = 0;  // raw closest-hit rays per second on the device, and on Embree
  double rate(double ms) const { return ms > 0 ? rays / (ms * 1e-3) : 0.0; }
  double ratio() const {
    const StageTimes& c = vc.times;
    return c.trace > 0 ? (c.features + c.sharpness + c.blur) / c.trace : 0;
  }
  double trace_vs_raw() const { return raw > 0 ? rate(vc.times.trace) / raw : 0; }
  double cpu_trace_vs_raw() const { return raw_cpu > 0 ? rate(vc.cpu.trace) / raw_cpu : 0; }
  double speedup() const { return vc.times.total > 0 ? vc.cpu.total / vc.times.total : 0; }
};

std::string vision_table_header(bool cuda) {
  return cuda ? std::string(
                    "| scene | size | device | trace ms | features ms | sharpness ms | blur ms | step ms | CPU step ms | CPU / GPU | GPU "
                    "trace / raw | CPU trace / raw | same fixations | corners first differ at step | perceived mean abs diff |\n"
                    "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
              : std::string(
                    "| scene | size | trace ms | features ms | sharpness ms | blur ms | impairments ms (media + retina + colour) | total "
                    "ms | (features+sharpness+blur) / trace | "
                    "impairments / trace | trace / raw Embree |\n"
                    "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

// The row on stdout.
void print_vision_row(const VisionRow& r, const Impairments& impair, bool cuda) {
  const StageTimes& c = r.vc.times;
  if (impair.any())
    fmt::print("  {:<28} {:>9}  impairments {:6.2f} ms (media {:.2f}, retina {:.2f}, colour {:.2f}) = {:.2f} of the trace stage\n", r.scene,
               r.size, c.impair.total_ms, c.impair.media_ms, c.impair.field_ms, c.impair.colour_ms,
               c.trace > 0 ? c.impair.total_ms / c.trace : 0.0);
  fmt::print(
      "  {:<28} {:>9}  trace {:6.2f}  features {:6.2f}  sharpness {:6.2f}  blur {:6.2f}  total {:6.2f} ms  (rest/trace {:.2f})\n"
      "  {:<28} {:>9}  trace {:.0f} Mrays/s = {:.2f} of raw {} closest-hit tracing of the same rays ({:.0f} Mrays/s)\n",
      r.scene, r.size, c.trace, c.features, c.sharpness, c.blur, c.total, r.ratio(), "", "", r.rate(c.trace) / 1e6, r.trace_vs_raw(),
      cuda ? "GPU" : "Embree", r.raw / 1e6);
  if (!cuda) return;
  // The same case on the CPU, step for step in the same run: the ratio, and how far the devices agree
  const StageTimes& cpu = r.vc.cpu;
  const Agreement& g = r.vc.agreement;
  const std::string parted =
      g.first_corner_difference == 0
          ? std::string("the corners identical at every step")
          : fmt::format("the corners first differ at step {} ({} of {} corners; {} of {} grey pixels differ)", g.first_corner_difference,
                        g.corners_differing, g.corners_total, g.grey_px_differing, g.grey_px);
  fmt::print(
      "  {:<28} {:>9}  CPU: trace {:6.2f}  features {:6.2f}  sharpness {:6.2f}  blur {:6.2f}  total {:6.2f} ms  → GPU {:.1f}× faster\n"
      "  {:<28} {:>9}  CPU: trace {:.0f} Mrays/s = {:.2f} of raw Embree closest-hit tracing of the same rays ({:.0f} Mrays/s)\n"
      "  {:<28} {:>9}  same fixations for {}/{} steps, {}; perceived mean |diff| ≤ {:.2e} while the same\n",
      "", "", cpu.trace, cpu.features, cpu.sharpness, cpu.blur, cpu.total, r.speedup(), "", "", r.rate(cpu.trace) / 1e6,
      r.cpu_trace_vs_raw(), r.raw_cpu / 1e6, "", "", g.same_fixations, g.steps, parted, g.perceived_mean_abs_diff);
}

// The row in the JSON (--json's "rows").
nlohmann::json vision_row_json(const VisionRow& r, const Impairments& impair, ComputeDevice device, int steps, int threads) {
  const StageTimes& c = r.vc.times;
  nlohmann::json row = {
      {"scene", r.scene},
      {"triangles", r.triangles},
      {"size", r.size},
      {"steps", steps - 1},
      {"device", to_string(device)},
      {"time_ms", {{"trace", c.trace}, {"features", c.features}, {"sharpness", c.sharpness}, {"blur", c.blur}, {"total", c.total}}},
      {"non_tracing_over_trace", r.ratio()},
      {"impairments", impair.describe()},
      {"impairments_ms",
       {{"media", c.impair.media_ms}, {"retina", c.impair.field_ms}, {"colour", c.impair.colour_ms}, {"total", c.impair.total_ms}}},
      {"impairments_over_trace", c.trace > 0 ? c.impair.total_ms / c.trace : 0.0},
      {"trace_rays_per_second", r.rate(c.trace)},
      {"raw_closest_hit_rays_per_second", r.raw},
      {"trace_over_raw", r.trace_vs_raw()}};
  if (device != ComputeDevice::cuda) return row;
  const StageTimes& cpu = r.vc.cpu;
  const Agreement& g = r.vc.agreement;
  row["cpu"] = {
      {"time_ms",
       {{"trace", cpu.trace}, {"features", cpu.features}, {"sharpness", cpu.sharpness}, {"blur", cpu.blur}, {"total", cpu.total}}},
      {"threads", threads},
      {"trace_rays_per_second", r.rate(cpu.trace)},
      {"raw_closest_hit_rays_per_second", r.raw_cpu},
      {"trace_over_raw", r.cpu_trace_vs_raw()}};
  row["cpu_over_gpu"] = r.speedup();
  row["agreement"] = {{"steps", g.steps},
                      {"same_fixations", g.same_fixations},
                      {"first_corner_difference_step", g.first_corner_difference},
                      {"corners_differing", g.corners_differing},
                      {"corners_gpu", g.corners_total},
                      {"grey_px_differing", g.grey_px_differing},
                      {"grey_px", g.grey_px},
                      {"perceived_mean_abs_diff", g.perceived_mean_abs_diff}};
  return row;
}

// The row in the Markdown table.
std::string vision_row_markdown(const VisionRow& r, bool cuda) {
  const StageTimes& c = r.vc.times;
  if (!cuda)
    return fmt::format(
        "| {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} ({:.1f} + {:.1f} + {:.1f}) | {:.1f} | {:.2f} | {:.2f} | {:.2f} |\n",
        r.scene, r.size, c.trace, c.features, c.sharpness, c.blur, c.impair.total_ms, c.impair.media_ms, c.impair.field_ms,
        c.impair.colour_ms, c.total, r.ratio(), c.trace > 0 ? c.impair.total_ms / c.trace : 0.0, r.trace_vs_raw());
  const Agreement& g = r.vc.agreement;
  const std::string first = g.first_corner_difference == 0 ? std::string("–")
                                                           : fmt::format("{} ({}/{} corners, {} grey px)", g.first_corner_difference,
                                                                         g.corners_differing, g.corners_total, g.grey_px_differing);
  return fmt::format(
      "| {} | {} | {} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {:.1f} | {:.1f} | {:.2f} | {:.2f} | {}/{} | {} | {:.1e} |\n", r.scene,
      r.size, availability().name, c.trace, c.features, c.sharpness, c.blur, c.total, r.vc.cpu.total, r.speedup(), r.trace_vs_raw(),
      r.cpu_trace_vs_raw(), g.same_fixations, g.steps, first, g.perceived_mean_abs_diff);
}

int run_bench_vision(const BenchVisionOptions& o) {
  const ThreadScope threads(o.threads);
  const ComputeDevice device = choose_device(o.device);
  const bool cuda = device == ComputeDevice::cuda;
  std::vector<std::string> scenes = o.scenes;
  if (scenes.empty()) {
    if (const std::string conference = repository_scene("conference.json", kConferenceObj); !conference.empty())
      scenes.push_back(conference);
    scenes.push_back("builtin:box");
  }
  const EyeSpec eye_spec = resolve_eye(o.eye, {o.pupil, std::nullopt});
  const Impairments impair = o.impairments == "none" ? Impairments{} : parse_eye_spec(o.impairments).impair;
  nlohmann::json rows = nlohmann::json::array();
  std::string md = vision_table_header(cuda);
  fmt::print("foveal bench vision: {} steps per case (median of steps 2…), features every step, eye {}, {} threads\n", o.steps, o.eye,
             threads.threads());
  fmt::print("  device   {}\n", describe_device(device));
  for (const std::string& spec : scenes) {
    const Scene scene = load_scene(spec);
    const Tracer tracer(scene);
    const Camera camera = first_camera(scene);
    std::unique_ptr<gpu::Renderer> raw_gpu;  // the GPU's raw closest-hit baseline (its own copy of the scene)
    if (cuda) raw_gpu = std::make_unique<gpu::Renderer>(scene);
    for (const std::string& size_text : o.sizes) {
      const glm::ivec2 size = parse_size("--size", size_text);
      SimulateParams p;
      p.width = size.x;
      p.height = size.y;
      p.eye = eye_spec.eye;
      p.impair = impair;
      p.seed = o.seed;
      p.features_every_step = true;  // the paper's timing: corners every step
      p.cuda = cuda;
      VisionRow r;
      r.scene = scene.source;
      r.size = size_text;
      r.triangles = tracer.triangles();
      r.vc = run_vision_case(tracer, scene, camera, p, o.steps, cuda);
      // The trace stage's primary-ray rate against raw closest-hit tracing of the same rays
      const std::vector<Ray> rays = primary_rays_in_tiles(camera, size.x, size.y);
      r.rays = rays.size();
      r.raw_cpu = raw_embree_rate(tracer, rays);
      r.raw = cuda ? raw_gpu->measure_intersection_rate(rays, 5) : r.raw_cpu;
      print_vision_row(r, impair, cuda);
      rows.push_back(vision_row_json(r, impair, device, o.steps, threads.threads()));
      md += vision_row_markdown(r, cuda);
    }
  }
  if (!o.json.empty())
    write_json_file(o.json, {{"threads", threads.threads()},
                             {"eye", o.eye},
                             {"optics", optics_json(eye_spec.eye)},
                             {"device", describe_device(device)},
                             {"rows", rows}});
  if (!o.markdown.empty()) write_text_file(o.markdown, md);
  return 0;
}

}  // namespace

std::function<int()> add_bench_vision_command(CLI::App& bench) {
  auto* cmd = bench.add_subcommand("vision", "the second paper's Table 1: milliseconds per stage of a simulation step");

  auto o = std::make_shared<BenchVisionOptions>();
  cmd->add_option("--scene", o->scenes, "scenes (default: scenes/conference.json when ../shared/data has it, and builtin:box)")
      ->delimiter(',');
  cmd->add_option("--size", o->sizes, "sizes WxH")->delimiter(',')->capture_default_str();
  cmd->add_option("--steps", o->steps, "steps per case (median reported; the first is left out as warm-up)")
      ->capture_default_str()
      ->check(CLI::Range(2, 10000));
  cmd->add_option("--eye", o->eye, "the eye's optics: presets or a profile .json, as for simulate")->capture_default_str();
  cmd->add_option("--pupil", o->pupil, "pupil diameter, mm (overrides a profile's pupil_mm; default: the profile's, else 3.5)");
  cmd->add_option("--impairments", o->impairments,
                  "impairments timed after the optics in every step (presets as for simulate --eye; 'none' for the paper's step alone)")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "seed of the saccades")->capture_default_str();
  cmd->add_option("--threads", o->threads, "worker threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
  cmd->add_option("--json", o->json, "write the table as JSON")->check(output_file());
  cmd->add_option("--markdown", o->markdown, "write the table as Markdown")->check(output_file());
  cmd->add_option("--device", o->device,
                  "where the steps run: cpu, cuda (then the CPU runs the same cases in the same run, for the ratio and "
                  "the agreement), or auto (cuda when a usable NVIDIA GPU is present)")
      ->capture_default_str();

  return [o] { return run_bench_vision(*o); };
}

}  // namespace foveal::app
