// foveal/experiments/ao_benchmark.cpp — the paper's speed-up table, measured.
#include "foveal/experiments/ao_benchmark.h"

#include "foveal/util/error.h"
#include "foveal/util/timer.h"

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstring>
#include <map>

#include "foveal/util/stats.h"

namespace foveal {
Frame timed_frame(const Tracer& tracer, const Scene& scene, const Camera& camera, const RenderParams& p, int repeats, double& median_ms) {
  std::vector<double> times;
  Frame frame;
  for (int r = 0; r < std::max(1, repeats); ++r) {
    frame = render_frame(tracer, scene, camera, p);
    times.push_back(frame.stats.total_ms);
  }
  median_ms = median(times);
  return frame;
}

// Centre of the pixels that see the material with the most triangles (the object, not the walls).
glm::dvec2 object_gaze(const Scene& scene, const Frame& frame) {
  std::map<uint32_t, size_t> count;
  for (uint32_t m : scene.material_ids) ++count[m];
  uint32_t object = 0;
  size_t best = 0;
  for (auto [m, c] : count)
    if (c > best) best = c, object = m;
  const GBuffer& g = frame.gbuffer;
  glm::dvec2 sum(0.0);
  size_t n = 0;
  for (size_t i = 0; i < g.prim.size(); ++i)
    if (g.hit(i) && scene.material_ids[g.prim[i]] == object) {
      sum += glm::dvec2(i % g.width + 0.5, i / g.width + 0.5);
      ++n;
    }
  if (n == 0) return {g.width * 0.5, g.height * 0.5};
  // The object pixel nearest to the centroid
  const glm::dvec2 c = sum / static_cast<double>(n);
  double best_d = 1e300;
  glm::dvec2 pick = c;
  for (size_t i = 0; i < g.prim.size(); ++i)
    if (g.hit(i) && scene.material_ids[g.prim[i]] == object) {
      const glm::dvec2 p(i % g.width + 0.5, i / g.width + 0.5);
      const double d = glm::dot(p - c, p - c);
      if (d < best_d) best_d = d, pick = p;
    }
  return pick;
}

std::vector<std::pair<std::string, glm::dvec2>> benchmark_gazes(const Scene& scene, const Frame& reference) {
  const double w = reference.gbuffer.width, h = reference.gbuffer.height;
  return {{"centre", {w * 0.5, h * 0.5}},       {"top-left", {0.5, 0.5}},
          {"top-right", {w - 0.5, 0.5}},        {"bottom-left", {0.5, h - 0.5}},
          {"bottom-right", {w - 0.5, h - 0.5}}, {"object", object_gaze(scene, reference)}};
}

namespace {

// AO rays of each tile of a frame (the tiles of trace_ao).
std::vector<uint64_t> tile_rays(const Frame& f) {
  const int w = f.gbuffer.width, h = f.gbuffer.height, tiles_x = ao_tiles_x(w);
  std::vector<uint64_t> rays(static_cast<size_t>(ao_tile_count(w, h)), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (f.gbuffer.hit(i)) rays[static_cast<size_t>((y / kTileSize) * tiles_x + x / kTileSize)] += f.maps.rays[i];
    }
  return rays;
}

}  // namespace

void run_ao_table(const Scene& scene, const std::vector<std::string>& camera_names, const RenderParams& base, AoTableDevice& device) {
  validate(base);
  std::vector<Camera> cameras;
  if (camera_names.empty()) cameras = scene.cameras.empty() ? std::vector<Camera>{default_camera(scene)} : scene.cameras;
  for (const auto& name : camera_names) cameras.push_back(find_camera(scene, name));
  for (const Camera& camera : cameras) {
    RenderParams full = base;
    full.mode = RenderMode::full;
    const Frame reference = device.reference(camera, full);
    for (const auto& [label, gaze] : benchmark_gazes(scene, reference)) {
      AoTableCase c{label, gaze, base};
      c.params.mode = RenderMode::foveated;
      c.params.gaze_px = gaze;
      device.gaze_case(camera, c, reference);
    }
  }
}

FoveaCheck fovea_check(const Frame& frame, const Frame& reference) {
  FoveaCheck check;
  for (size_t i = 0; i < frame.maps.quality.size(); ++i)
    if (frame.maps.quality[i] >= 1.0f) {
      ++check.pixels;
      check.identical &= std::memcmp(&frame.color.pixels[3 * i], &reference.color.pixels[3 * i], 3 * sizeof(float)) == 0;
    }
  return check;
}

namespace {

// The table on the CPU: render_frame over Embree, each camera's AO pass against raw Embree on the
// same rays, and the cost each kept ray had in its tile of the reference.
class CpuTable final : public AoTableDevice {
 public:
  CpuTable(const Scene& scene, const Tracer& tracer, const AoBenchParams& params, AoBenchResult& result,
           const std::function<void(const std::string&)>& say)
      : scene_(scene), tracer_(tracer), params_(params), result_(result), say_(say) {}

  Frame reference(const Camera& camera, const RenderParams& full) override {
    AoBenchCamera& cam = result_.cameras.emplace_back();
    cam.name = camera.name;
    Frame reference = timed_frame(tracer_, scene_, camera, full, params_.repeats, cam.full_ms);
    cam.full_fps = 1000.0 / cam.full_ms;
    cam.full_ao_rays_per_pixel = reference.stats.ao_rays_mean;
    cam.full_ao_rays_per_second = reference.stats.ao_rays / (reference.stats.ao_ms / 1000.0);
    say_(fmt::format("{}: full frame {:.0f} ms ({:.2f} fps), {:.1f} Mrays/s", camera.name, cam.full_ms, cam.full_fps,
                     cam.full_ao_rays_per_second / 1e6));
    measure_raw(camera, reference, cam);
    return reference;
  }

  void gaze_case(const Camera& camera, const AoTableCase& t, const Frame& reference) override {
    AoBenchCamera& cam = result_.cameras.back();
    AoBenchCase c;
    c.camera = camera.name;
    c.gaze_label = t.label;
    c.gaze_px = t.gaze_px;
    const Frame frame = timed_frame(tracer_, scene_, camera, t.params, params_.repeats, c.foveated_ms);
    c.foveated_fps = 1000.0 / c.foveated_ms;
    c.speedup = cam.full_ms / c.foveated_ms;
    c.speedup_pct = (c.foveated_fps - cam.full_fps) / cam.full_fps * 100.0;
    c.ao_rays_per_pixel = frame.stats.ao_rays_mean;
    c.ao_rays_per_second = frame.stats.ao_ms > 0 ? frame.stats.ao_rays / (frame.stats.ao_ms / 1000.0) : 0;
    c.ao_ray_ratio = frame.stats.ao_rays > 0 ? static_cast<double>(reference.stats.ao_rays) / frame.stats.ao_rays : 0;
    c.efficiency = c.ao_ray_ratio > 0 ? c.speedup / c.ao_ray_ratio : 0;
    // Expected foveated time if each kept ray cost what it cost in the reference's tile
    const std::vector<uint64_t> rays = tile_rays(frame);
    double expected_ao_ms = 0;
    for (size_t k = 0; k < tile_cost_.size(); ++k)
      if (reference_tile_rays_[k] > 0) expected_ao_ms += tile_cost_[k] * rays[k] / static_cast<double>(reference_tile_rays_[k]);
    const double fixed_ms = frame.stats.total_ms - frame.stats.ao_ms;
    c.cost_ratio = cam.full_ms / (expected_ao_ms + fixed_ms);
    c.cost_efficiency = c.speedup / c.cost_ratio;
    const FoveaCheck fovea = fovea_check(frame, reference);
    c.fovea_identical = fovea.identical;
    c.fovea_pixels = fovea.pixels;
    say_(fmt::format("{} / {}: {:.0f} ms ({:.2f} fps), speed-up {:.2f}x, {:.1f} rays/px, fovea {} ({} px)", camera.name, t.label,
                     c.foveated_ms, c.foveated_fps, c.speedup, c.ao_rays_per_pixel, c.fovea_identical ? "identical" : "DIFFERS",
                     c.fovea_pixels));
    cam.cases.push_back(c);
  }

 private:
  // Raw Embree throughput on the same rays (a sample of the reference's pixels), interleaved with
  // the renderer's AO pass on the reference frame so both see the same machine load
  void measure_raw(const Camera& camera, const Frame& reference, AoBenchCamera& cam) {
    std::vector<Ray> sample;
    const float ao_distance = reference.stats.ao_distance, epsilon = surface_epsilon(scene_.bounds());
    collect_ao_rays(reference.gbuffer, reference.maps, ao_distance, epsilon, params_.render.seed, params_.raw_stride, sample);
    std::vector<double> raw[3], pass_ms;
    std::vector<std::vector<double>> tile_ms;  // per round, per tile
    std::vector<float> visibility;
    uint64_t pass_rays = 0;
    for (int round = 0; round < std::max(5, params_.repeats); ++round) {
      for (TraceApi api : {TraceApi::single, TraceApi::packet8, TraceApi::stream})
        raw[static_cast<int>(api)].push_back(measure_raw_occlusion(tracer_, sample, api).rays_per_second);
      const Timer timer;
      AoPassHooks hooks;
      hooks.tile_ms = &tile_ms.emplace_back();
      pass_rays = trace_ao(tracer_, reference.gbuffer, reference.maps, ao_distance, epsilon, params_.render.seed, visibility, hooks);
      pass_ms.push_back(timer.ms());
    }
    for (int api = 0; api < 3; ++api) cam.raw_rays_per_second[api] = median(raw[api]);
    cam.ao_pass_rays_per_second = pass_rays / (median(pass_ms) / 1000.0);
    // Cost of each tile's rays in the reference: median over rounds, scaled so tiles add up to the pass's wall time
    const size_t tiles = tile_ms.front().size();
    tile_cost_.assign(tiles, 0.0);
    for (size_t t = 0; t < tiles; ++t) {
      std::vector<double> v;
      for (const auto& round : tile_ms) v.push_back(round[t]);
      tile_cost_[t] = median(v);
    }
    double cost_sum = 0;
    for (double c : tile_cost_) cost_sum += c;
    for (double& c : tile_cost_) c *= median(pass_ms) / cost_sum;
    reference_tile_rays_ = tile_rays(reference);
    // The ratio of each round, then the median: load that drifts between rounds cancels out
    std::vector<double> ratios;
    const auto& raw_same_api = raw[static_cast<int>(tracer_.occlusion_api())];
    for (size_t r = 0; r < pass_ms.size(); ++r) ratios.push_back(pass_rays / (pass_ms[r] / 1000.0) / raw_same_api[r]);
    cam.renderer_vs_raw = median(ratios);
    say_(
        fmt::format("{}: raw Embree occlusion on {} rays: single {:.1f}, packet8 {:.1f}, stream {:.1f} Mrays/s; "
                    "renderer AO pass {:.1f} Mrays/s, renderer/raw {:.3f}",
                    camera.name, sample.size(), cam.raw_rays_per_second[0] / 1e6, cam.raw_rays_per_second[1] / 1e6,
                    cam.raw_rays_per_second[2] / 1e6, cam.ao_pass_rays_per_second / 1e6, cam.renderer_vs_raw));
  }

  const Scene& scene_;
  const Tracer& tracer_;
  const AoBenchParams& params_;
  AoBenchResult& result_;
  const std::function<void(const std::string&)>& say_;
  std::vector<double> tile_cost_;              // the reference's AO cost per tile, ms
  std::vector<uint64_t> reference_tile_rays_;  // and its rays per tile
};

}  // namespace

AoBenchResult run_ao_benchmark(const Scene& scene, const Tracer& tracer, const AoBenchParams& params,
                               const std::function<void(const std::string&)>& progress) {
  const std::function<void(const std::string&)> say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  AoBenchResult result;
  result.scene = scene.source;
  result.triangles = tracer.triangles();
  result.build_ms = tracer.build_ms();
  result.threads = static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  result.trace_api = to_string(tracer.occlusion_api());
  CpuTable table(scene, tracer, params, result, say);
  run_ao_table(scene, params.cameras, params.render, table);
  return result;
}

nlohmann::json to_json(const AoBenchResult& r) {
  nlohmann::json j;
  j["scene"] = r.scene;
  j["triangles"] = r.triangles;
  j["build_ms"] = r.build_ms;
  j["threads"] = r.threads;
  j["trace_api"] = r.trace_api;
  for (const auto& cam : r.cameras) {
    nlohmann::json c;
    c["camera"] = cam.name;
    c["full"] = {{"ms", cam.full_ms},
                 {"fps", cam.full_fps},
                 {"ao_rays_per_pixel", cam.full_ao_rays_per_pixel},
                 {"ao_rays_per_second", cam.full_ao_rays_per_second}};
    c["raw_embree_rays_per_second"] = {
        {"single", cam.raw_rays_per_second[0]}, {"packet8", cam.raw_rays_per_second[1]}, {"stream", cam.raw_rays_per_second[2]}};
    c["renderer_ao_pass_rays_per_second"] = cam.ao_pass_rays_per_second;
    c["renderer_vs_raw"] = cam.renderer_vs_raw;
    for (const auto& k : cam.cases)
      c["gaze"].push_back({{"label", k.gaze_label},
                           {"gaze_px", {k.gaze_px.x, k.gaze_px.y}},
                           {"ms", k.foveated_ms},
                           {"fps", k.foveated_fps},
                           {"speedup", k.speedup},
                           {"speedup_pct", k.speedup_pct},
                           {"ao_rays_per_pixel", k.ao_rays_per_pixel},
                           {"ao_rays_per_second", k.ao_rays_per_second},
                           {"ao_ray_ratio", k.ao_ray_ratio},
                           {"efficiency", k.efficiency},
                           {"cost_weighted_ratio", k.cost_ratio},
                           {"cost_efficiency", k.cost_efficiency},
                           {"fovea_identical", k.fovea_identical},
                           {"fovea_pixels", k.fovea_pixels}});
    j["cameras"].push_back(c);
  }
  return j;
}

std::string to_markdown(const AoBenchResult& r) {
  std::string s = fmt::format("Scene `{}` ({} triangles, BVH {:.0f} ms), {} threads, occlusion API `{}`\n\n", r.scene, r.triangles,
                              r.build_ms, r.threads, r.trace_api);
  s += "| camera | gaze | full fps | foveated fps | speed-up | speed-up % | AO rays/px | AO Mrays/s | ray ratio | time/rays | "
       "cost ratio | time/cost | fovea identical |\n";
  s += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const auto& cam : r.cameras) {
    s += fmt::format("| {} | (full frame) | {:.3f} | | | | {:.1f} | {:.2f} | | | | | |\n", cam.name, cam.full_fps,
                     cam.full_ao_rays_per_pixel, cam.full_ao_rays_per_second / 1e6);
    for (const auto& k : cam.cases)
      s += fmt::format(
          "| {} | {} ({:.0f}, {:.0f}) | | {:.3f} | {:.2f}x | {:.0f}% | {:.1f} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {} ({} px) "
          "|\n",
          cam.name, k.gaze_label, k.gaze_px.x, k.gaze_px.y, k.foveated_fps, k.speedup, k.speedup_pct, k.ao_rays_per_pixel,
          k.ao_rays_per_second / 1e6, k.ao_ray_ratio, k.efficiency, k.cost_ratio, k.cost_efficiency, k.fovea_identical ? "yes" : "NO",
          k.fovea_pixels);
  }
  s += "\n| camera | raw Embree single Mrays/s | packet8 | stream | renderer AO pass Mrays/s | renderer / raw (same API) |\n";
  s += "|---|---:|---:|---:|---:|---:|\n";
  for (const auto& cam : r.cameras)
    s += fmt::format("| {} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {:.3f} |\n", cam.name, cam.raw_rays_per_second[0] / 1e6,
                     cam.raw_rays_per_second[1] / 1e6, cam.raw_rays_per_second[2] / 1e6, cam.ao_pass_rays_per_second / 1e6,
                     cam.renderer_vs_raw);
  return s;
}

}  // namespace foveal
