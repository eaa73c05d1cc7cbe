// foveal/experiments/ao_benchmark.h — the first paper's Table 1: full-frame vs foveated AO speed for
// several cameras and gaze points, with the renderer's AO rate against raw Embree throughput.
#pragma once

#include "foveal/render/render.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace foveal {

// What to measure.
struct AoBenchParams {
  RenderParams render;               // size, display, n_max, γ, … (mode and gaze are set per case)
  std::vector<std::string> cameras;  // empty → every camera of the scene (or the default one)
  int repeats = 1;                   // frames per case; the median time is reported
  size_t raw_stride = 32;            // every k-th pixel's AO rays form the raw-throughput sample
};

// One gaze point of one camera.
struct AoBenchCase {
  std::string camera, gaze_label;
  glm::dvec2 gaze_px{0.0};
  double foveated_ms = 0, foveated_fps = 0;
  double speedup_pct = 0;        // (fps − full fps) / full fps × 100, the paper's definition
  double speedup = 0;            // full time / foveated time
  double ao_rays_per_pixel = 0;  // mean over all pixels
  double ao_rays_per_second = 0;
  double ao_ray_ratio = 0;       // full-frame AO rays / foveated AO rays
  double efficiency = 0;         // speedup / ao_ray_ratio (1 = time saved exactly as rays saved)
  double cost_ratio = 0;         // full time / expected foveated time, each kept ray costing what it cost
                                 // in its 16×16 tile of the reference
  double cost_efficiency = 0;    // speedup / cost_ratio (1 = foveation itself costs nothing)
  bool fovea_identical = false;  // q = 1 pixels bit-identical to the full-frame reference
  size_t fovea_pixels = 0;
};

// One camera: the full-frame reference, its gaze cases and the raw Embree baseline.
struct AoBenchCamera {
  std::string name;
  double full_ms = 0, full_fps = 0, full_ao_rays_per_pixel = 0, full_ao_rays_per_second = 0;
  double raw_rays_per_second[3] = {0, 0, 0};  // indexed by TraceApi: single, packet8, stream
  double ao_pass_rays_per_second = 0;         // the renderer's AO pass on the reference frame (median)
  double renderer_vs_raw = 0;                 // renderer's AO pass rate / raw rate with the same API: median over interleaved rounds
  std::vector<AoBenchCase> cases;
};

// The whole table.
struct AoBenchResult {
  std::string scene;
  size_t triangles = 0;
  double build_ms = 0;
  int threads = 0;
  std::string trace_api;
  std::vector<AoBenchCamera> cameras;
};

// The median frame time of `repeats` renders (the frame itself is the same every time), and the frame.
Frame timed_frame(const Tracer& tracer, const Scene& scene, const Camera& camera, const RenderParams& p, int repeats, double& median_ms);

// The table's gaze points for a reference frame (its G-buffer): the centre, the four corner
// pixels, and the pixel nearest the centroid of the object (the material with most triangles).
std::vector<std::pair<std::string, glm::dvec2>> benchmark_gazes(const Scene& scene, const Frame& reference);
glm::dvec2 object_gaze(const Scene& scene, const Frame& reference);

// One harness for the table on either device (this file's CPU benchmark, gpu_benchmark.h's GPU
// one): for each camera (`camera_names`, or every camera of the scene when empty) its full-frame
// reference, then the gaze points of benchmark_gazes() foveated, each judged against it.
struct AoTableCase {
  std::string label;  // the gaze point's name
  glm::dvec2 gaze_px{0.0};
  RenderParams params;  // foveated at the gaze
};
class AoTableDevice {
 public:
  virtual ~AoTableDevice() = default;
  // A camera's full-frame reference (params in full mode), measured; returns its frame.
  virtual Frame reference(const Camera& camera, const RenderParams& full) = 0;
  // One gaze point, measured and judged against the camera's reference frame.
  virtual void gaze_case(const Camera& camera, const AoTableCase& c, const Frame& reference) = 0;
};
void run_ao_table(const Scene& scene, const std::vector<std::string>& camera_names, const RenderParams& base, AoTableDevice& device);
// The first paper's claim about the fovea: every q = 1 pixel of a foveated frame bit-identical to
// the full-frame reference's.
struct FoveaCheck {
  bool identical = true;
  size_t pixels = 0;  // the q = 1 pixels compared
};
FoveaCheck fovea_check(const Frame& frame, const Frame& reference);

// Run the benchmark; `progress` receives one line per finished measurement.
AoBenchResult run_ao_benchmark(const Scene& scene, const Tracer& tracer, const AoBenchParams& params,
                               const std::function<void(const std::string&)>& progress = {});

// The result as JSON and as a Markdown table.
nlohmann::json to_json(const AoBenchResult& result);
std::string to_markdown(const AoBenchResult& result);

}  // namespace foveal
