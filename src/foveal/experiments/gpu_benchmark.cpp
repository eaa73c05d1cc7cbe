// foveal/experiments/gpu_benchmark.cpp — GPU against CPU on the first paper's Table 1 setting.
#include "foveal/experiments/gpu_benchmark.h"

#include "foveal/experiments/ao_benchmark.h"
#include "foveal/util/error.h"
#include "foveal/util/stats.h"

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>

namespace foveal::gpu {
namespace {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  return "unknown CPU";
}

}  // namespace

Agreement compare_frames(const Frame& gpu, const Frame& cpu) {
  Agreement a;
  const size_t n = gpu.color.pixels.size() / 3;
  if (n == 0 || cpu.color.pixels.size() != gpu.color.pixels.size()) return a;
  size_t prim_same = 0, vis_same = 0, within = 0, with_rays = 0;
  double vis_abs = 0, vis_signed = 0, noise = 0;
  const bool have_vis = gpu.visibility.size() == n && cpu.visibility.size() == n;
  const bool have_rays = gpu.maps.rays.size() == n;
  for (size_t i = 0; i < n; ++i) {
    if (i < gpu.gbuffer.prim.size() && i < cpu.gbuffer.prim.size()) prim_same += gpu.gbuffer.prim[i] == cpu.gbuffer.prim[i];
    if (have_vis) {
      const double d = static_cast<double>(gpu.visibility[i]) - cpu.visibility[i];
      vis_same += d == 0;
      vis_abs += std::abs(d);
      vis_signed += d;
      const int rays = have_rays ? gpu.maps.rays[i] : 0;
      within += rays == 0 ? d == 0 : std::abs(d) * rays <= 2.0 + 1e-6;
      if (rays > 0 && gpu.gbuffer.prim.size() == n && gpu.gbuffer.hit(i)) {
        const double v = cpu.visibility[i];
        noise += std::sqrt(std::max(v * (1 - v), 1.0 / rays) / rays);  // at least one ray's worth of spread
        ++with_rays;
      }
    }
    for (int c = 0; c < 3; ++c)
      a.colour_max_abs = std::max<double>(a.colour_max_abs, std::abs(gpu.color.pixels[3 * i + c] - cpu.color.pixels[3 * i + c]));
  }
  a.primary_identical = static_cast<double>(prim_same) / n;
  a.visibility_identical = static_cast<double>(vis_same) / n;
  a.visibility_mean_abs = vis_abs / n;
  a.visibility_mean_signed = vis_signed / n;
  a.visibility_within_2_rays = static_cast<double>(within) / n;
  a.noise_ratio = with_rays > 0 && noise > 0 ? (vis_abs / n) / (noise / with_rays) : 0;
  return a;
}

namespace {

// The table on the GPU (gpu::Renderer, CUDA events), each case also on the CPU in the same run.
class GpuTable final : public AoTableDevice {
 public:
  GpuTable(const Scene& scene, const BenchParams& params, BenchResult& result, const std::function<void(const std::string&)>& say)
      : scene_(scene), params_(params), result_(result), say_(say), gpu_(scene) {
    if (params.cpu) tracer_ = std::make_unique<Tracer>(scene);
  }
  const Renderer& gpu() const { return gpu_; }

  Frame reference(const Camera& camera, const RenderParams& full) override {
    BenchCamera& cam = result_.cameras.emplace_back();
    cam.name = camera.name;
    BenchCase fc;
    fc.label = "(full frame)";
    Frame reference = measure(camera, full, fc);
    fc.speedup_vs_full = 1;
    fc.ray_ratio = 1;
    say_(fmt::format("{}: full frame GPU {:.2f} ms ({:.1f} fps), CPU {:.0f} ms, GPU/CPU speed {:.1f}x, {:.0f} Mrays/s", camera.name,
                     fc.gpu_ms, fc.gpu_fps, fc.cpu_ms, fc.gpu_speedup_over_cpu, fc.ao_rays_per_second / 1e6));
    cam.cases.push_back(fc);
    // The GPU's raw occlusion rate on a sample of the reference's own AO rays
    std::vector<Ray> sample;
    collect_ao_rays(reference.gbuffer, reference.maps, reference.stats.ao_distance, surface_epsilon(scene_.bounds()), params_.render.seed,
                    params_.raw_stride, sample);
    cam.raw_sample = sample.size();
    cam.raw_rays_per_second = gpu_.measure_occlusion_rate(sample, std::max(3, params_.repeats));
    cam.renderer_ao_rays_per_second = fc.ao_rays_per_second;
    cam.renderer_vs_raw = cam.raw_rays_per_second > 0 ? cam.renderer_ao_rays_per_second / cam.raw_rays_per_second : 0;
    say_(fmt::format("{}: raw GPU occlusion {:.0f} Mrays/s on {} rays, renderer AO pass {:.0f} Mrays/s, ratio {:.2f}", camera.name,
                     cam.raw_rays_per_second / 1e6, sample.size(), cam.renderer_ao_rays_per_second / 1e6, cam.renderer_vs_raw));
    return reference;
  }

  void gaze_case(const Camera& camera, const AoTableCase& t, const Frame& reference) override {
    BenchCamera& cam = result_.cameras.back();
    const BenchCase& fc = cam.cases.front();
    BenchCase c;
    c.label = t.label;
    c.gaze_px = t.gaze_px;
    const Frame frame = measure(camera, t.params, c);
    c.speedup_vs_full = fc.gpu_ms / c.gpu_ms;
    c.ray_ratio = frame.stats.ao_rays > 0 ? static_cast<double>(reference.stats.ao_rays) / frame.stats.ao_rays : 0;
    c.fovea_identical = fovea_check(frame, reference).identical;
    say_(
        fmt::format("{} / {}: GPU {:.2f} ms ({:.0f} fps), CPU {:.0f} ms, GPU/CPU {:.1f}x, vs full {:.2f}x (rays {:.2f}x), "
                    "AO balanced {:.2f} ms vs per-pixel {:.2f} ms",
                    camera.name, t.label, c.gpu_ms, c.gpu_fps, c.cpu_ms, c.gpu_speedup_over_cpu, c.speedup_vs_full, c.ray_ratio,
                    c.passes.ao_ms, c.per_pixel_ao_ms));
    cam.cases.push_back(c);
  }

 private:
  // One case: GPU frames (median), the per-pixel schedule's AO pass, the CPU frame; returns the GPU's frame
  Frame measure(const Camera& camera, const RenderParams& p, BenchCase& c) {
    std::vector<double> ms, ao_ms;
    std::vector<GpuPassTimes> passes;
    Frame frame;
    gpu_.set_ao_schedule(AoSchedule::balanced);
    gpu_.render(camera, p);  // warm-up (buffers, caches)
    for (int r = 0; r < std::max(1, params_.repeats); ++r) {
      frame = gpu_.render(camera, p);
      ms.push_back(gpu_.last_times().total_ms);
      passes.push_back(gpu_.last_times());
    }
    c.gpu_ms = median(ms);
    c.gpu_fps = 1000.0 / c.gpu_ms;
    const auto mid = std::min_element(passes.begin(), passes.end(), [&](const GpuPassTimes& a, const GpuPassTimes& b) {
      return std::abs(a.total_ms - c.gpu_ms) < std::abs(b.total_ms - c.gpu_ms);
    });
    c.passes = *mid;
    c.ao_rays_per_pixel = frame.stats.ao_rays_mean;
    c.ao_rays_per_second = c.passes.ao_ms > 0 ? frame.stats.ao_rays / (c.passes.ao_ms * 1e-3) : 0;
    gpu_.set_ao_schedule(AoSchedule::per_pixel);
    for (int r = 0; r < std::max(1, params_.repeats); ++r) {
      gpu_.render(camera, p, FrameOutputs::colour_only());
      ao_ms.push_back(gpu_.last_times().ao_ms);
    }
    c.per_pixel_ao_ms = median(ao_ms);
    gpu_.set_ao_schedule(AoSchedule::balanced);
    if (tracer_) {
      std::vector<double> cpu_ms;
      Frame cpu_frame;
      for (int r = 0; r < std::max(1, params_.cpu_repeats); ++r) {
        cpu_frame = render_frame(*tracer_, scene_, camera, p);
        cpu_ms.push_back(cpu_frame.stats.total_ms);
      }
      c.cpu_ms = median(cpu_ms);
      c.cpu_fps = 1000.0 / c.cpu_ms;
      c.gpu_speedup_over_cpu = c.cpu_ms / c.gpu_ms;
      c.vs_cpu = compare_frames(frame, cpu_frame);
    }
    return frame;
  }

  const Scene& scene_;
  const BenchParams& params_;
  BenchResult& result_;
  const std::function<void(const std::string&)>& say_;
  Renderer gpu_;
  std::unique_ptr<Tracer> tracer_;  // with params.cpu: the CPU's frames of the same cases
};

}  // namespace

BenchResult run_benchmark(const Scene& scene, const BenchParams& params, const std::function<void(const std::string&)>& progress) {
  const std::function<void(const std::string&)> say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  validate(params.render);
  BenchResult result;
  result.scene = scene.source;
  result.device = availability().describe();
  result.cpu = cpu_model();
  result.cpu_threads = static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  result.width = params.render.width;
  result.height = params.render.height;
  result.max_rays = params.render.foveation.max_rays;
  GpuTable table(scene, params, result, say);
  result.triangles = scene.triangles.size();
  result.bvh_nodes = table.gpu().bvh().nodes.size();
  result.bvh_depth = table.gpu().bvh().depth;
  result.bvh_build_ms = table.gpu().bvh().build_ms;
  result.bvh_sah_cost = table.gpu().bvh().sah_cost;
  run_ao_table(scene, params.cameras, params.render, table);
  return result;
}

nlohmann::json to_json(const BenchResult& r) {
  nlohmann::json j;
  j["scene"] = r.scene;
  j["device"] = r.device;
  j["cpu"] = r.cpu;
  j["cpu_threads"] = r.cpu_threads;
  j["size"] = {r.width, r.height};
  j["max_rays"] = r.max_rays;
  j["bvh"] = {{"triangles", r.triangles},
              {"nodes", r.bvh_nodes},
              {"depth", r.bvh_depth},
              {"build_ms", r.bvh_build_ms},
              {"sah_cost", r.bvh_sah_cost}};
  for (const auto& cam : r.cameras) {
    nlohmann::json c;
    c["camera"] = cam.name;
    c["raw_gpu_occlusion_rays_per_second"] = cam.raw_rays_per_second;
    c["raw_sample_rays"] = cam.raw_sample;
    c["renderer_ao_rays_per_second"] = cam.renderer_ao_rays_per_second;
    c["renderer_vs_raw"] = cam.renderer_vs_raw;
    for (const auto& k : cam.cases)
      c["cases"].push_back({{"label", k.label},
                            {"gaze_px", {k.gaze_px.x, k.gaze_px.y}},
                            {"gpu_ms", k.gpu_ms},
                            {"gpu_fps", k.gpu_fps},
                            {"cpu_ms", k.cpu_ms},
                            {"cpu_fps", k.cpu_fps},
                            {"gpu_speedup_over_cpu", k.gpu_speedup_over_cpu},
                            {"speedup_vs_full", k.speedup_vs_full},
                            {"ray_ratio", k.ray_ratio},
                            {"ao_rays_per_pixel", k.ao_rays_per_pixel},
                            {"ao_rays_per_second", k.ao_rays_per_second},
                            {"pass_ms",
                             {{"primary", k.passes.primary_ms},
                              {"foveation", k.passes.foveation_ms},
                              {"scan", k.passes.scan_ms},
                              {"ao", k.passes.ao_ms},
                              {"shade", k.passes.shade_ms}}},
                            {"per_pixel_schedule_ao_ms", k.per_pixel_ao_ms},
                            {"fovea_identical_to_full", k.fovea_identical},
                            {"vs_cpu",
                             {{"primary_identical", k.vs_cpu.primary_identical},
                              {"visibility_identical", k.vs_cpu.visibility_identical},
                              {"visibility_mean_abs", k.vs_cpu.visibility_mean_abs},
                              {"visibility_mean_signed", k.vs_cpu.visibility_mean_signed},
                              {"visibility_within_2_rays", k.vs_cpu.visibility_within_2_rays},
                              {"difference_over_mc_noise", k.vs_cpu.noise_ratio},
                              {"colour_max_abs", k.vs_cpu.colour_max_abs}}}});
    j["cameras"].push_back(c);
  }
  return j;
}

std::string to_markdown(const BenchResult& r) {
  std::string s = fmt::format(
      "Scene `{}` ({} triangles; BVH {} nodes, depth {}, SAH cost {:.1f}, built in {:.0f} ms), {}x{}, n_max {}\n"
      "GPU: {}. CPU: {}, {} threads.\n\n",
      r.scene, r.triangles, r.bvh_nodes, r.bvh_depth, r.bvh_sah_cost, r.bvh_build_ms, r.width, r.height, r.max_rays, r.device, r.cpu,
      r.cpu_threads);
  s += "| camera | gaze | GPU ms | GPU fps | CPU ms | GPU/CPU | vs full (GPU) | rays saved | AO rays/px | GPU AO Mrays/s | "
       "AO ms balanced | AO ms per-pixel | fovea = full | primary = CPU | V = CPU | V within 2 rays | mean ΔV | mean abs ΔV / MC σ |\n";
  s += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|\n";
  for (const auto& cam : r.cameras)
    for (const auto& k : cam.cases)
      s += fmt::format(
          "| {} | {} | {:.2f} | {:.0f} | {:.0f} | {:.1f}x | {:.2f}x | {:.2f}x | {:.1f} | {:.0f} | {:.2f} | {:.2f} | {} | "
          "{:.5f} | {:.3f} | {:.4f} | {:+.1e} | {:.3f} |\n",
          cam.name, k.label, k.gpu_ms, k.gpu_fps, k.cpu_ms, k.gpu_speedup_over_cpu, k.speedup_vs_full, k.ray_ratio, k.ao_rays_per_pixel,
          k.ao_rays_per_second / 1e6, k.passes.ao_ms, k.per_pixel_ao_ms, k.fovea_identical ? "yes" : "NO", k.vs_cpu.primary_identical,
          k.vs_cpu.visibility_identical, k.vs_cpu.visibility_within_2_rays, k.vs_cpu.visibility_mean_signed, k.vs_cpu.noise_ratio);
  s += "\n| camera | raw GPU occlusion Mrays/s | renderer AO pass Mrays/s | renderer / raw |\n|---|---:|---:|---:|\n";
  for (const auto& cam : r.cameras)
    s += fmt::format("| {} | {:.0f} | {:.0f} | {:.2f} |\n", cam.name, cam.raw_rays_per_second / 1e6, cam.renderer_ao_rays_per_second / 1e6,
                     cam.renderer_vs_raw);
  return s;
}

}  // namespace foveal::gpu
