// foveal/experiments/gpu_benchmark.h — the first paper's Table 1 on the GPU, with the CPU in the same run.
//
// For each camera: the full-frame reference and the six gaze points of `bench ao`, each timed
// on the GPU (CUDA events around the passes) and on the CPU (render_frame, oneTBB + Embree), with
// the GPU/CPU ratio; the GPU's AO pass against the GPU's own raw occlusion rate on the same rays;
// the balanced ray schedule against one thread per pixel; and how far the GPU's image is from
// the CPU's (primary hits, AO visibility, colour).
#pragma once

#include "foveal/cuda/gpu.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace foveal::gpu {

struct BenchParams {
  RenderParams render;               // size, display, n_max, γ (mode and gaze per case)
  std::vector<std::string> cameras;  // empty → every camera of the scene
  int repeats = 5;                   // GPU frames per case (median); the CPU runs cpu_repeats
  int cpu_repeats = 1;
  bool cpu = true;        // also time the CPU
  size_t raw_stride = 4;  // every k-th reference pixel's AO rays: the raw-rate sample
};

// How the GPU frame differs from the CPU frame of the same parameters.
struct Agreement {
  double primary_identical = 0;         // fraction of pixels with the same primary triangle (or both missing)
  double visibility_identical = 0;      // fraction of pixels with bit-identical AO visibility
  double visibility_mean_abs = 0;       // mean |V_gpu − V_cpu| over pixels
  double visibility_mean_signed = 0;    // mean V_gpu − V_cpu (a bias, were there one)
  double visibility_within_2_rays = 0;  // fraction of pixels whose open-ray counts differ by at most 2
  double noise_ratio = 0;               // mean |ΔV| over the mean Monte-Carlo standard error √(V(1−V)/n) of pixels with rays
  double colour_max_abs = 0;            // largest |colour difference| of any channel
};
Agreement compare_frames(const Frame& gpu, const Frame& cpu);

struct BenchCase {
  std::string label;  // "(full frame)" or the gaze label
  glm::dvec2 gaze_px{0.0};
  double gpu_ms = 0, gpu_fps = 0, cpu_ms = 0, cpu_fps = 0, gpu_speedup_over_cpu = 0;
  double speedup_vs_full = 0;  // GPU full time / GPU time of this case
  double ray_ratio = 0;        // full AO rays / this case's AO rays
  double ao_rays_per_pixel = 0, ao_rays_per_second = 0;
  GpuPassTimes passes;          // of the median GPU frame
  double per_pixel_ao_ms = 0;   // the AO pass with one thread per pixel (median)
  bool fovea_identical = true;  // q = 1 pixels bit-identical to the GPU's full frame
  Agreement vs_cpu;
};

struct BenchCamera {
  std::string name;
  double raw_rays_per_second = 0;  // GPU occlusion kernel on the sampled reference rays
  double renderer_ao_rays_per_second = 0;
  double renderer_vs_raw = 0;
  size_t raw_sample = 0;
  std::vector<BenchCase> cases;  // [0] = full frame
};

struct BenchResult {
  std::string scene, device, cpu;
  size_t triangles = 0, bvh_nodes = 0;
  int bvh_depth = 0;
  double bvh_build_ms = 0, bvh_sah_cost = 0;
  int cpu_threads = 0;
  int width = 0, height = 0, max_rays = 0;
  std::vector<BenchCamera> cameras;
};

BenchResult run_benchmark(const Scene& scene, const BenchParams& params, const std::function<void(const std::string&)>& progress = {});
nlohmann::json to_json(const BenchResult& result);
std::string to_markdown(const BenchResult& result);

}  // namespace foveal::gpu
