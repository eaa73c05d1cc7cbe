// foveal/render/outputs.cpp — AOVs, budget mask, acuity plot and stats JSON.
#include "foveal/render/outputs.h"

#include "foveal/io/image_io.h"
#include "foveal/io/plot.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sys/resource.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace foveal {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

}  // namespace

std::vector<std::string> aov_names() {
  return {"ao", "depth", "position", "normal", "albedo", "budget", "quality", "blend", "eccentricity", "traced"};
}

Image aov_image(const Frame& f, const std::string& name) {
  const GBuffer& g = f.gbuffer;
  const bool rgb = name == "position" || name == "normal" || name == "albedo";
  Image image(g.width, g.height, rgb ? 3 : 1);
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const size_t i = static_cast<size_t>(y) * g.width + x;
      const bool hit = g.hit(i);
      if (rgb) {
        const glm::vec3 v = !hit ? glm::vec3(kNaN) : name == "position" ? g.position[i] : name == "normal" ? g.normal[i] : g.albedo[i];
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = v[c];
        continue;
      }
      float v = 0;
      if (name == "ao")
        v = hit ? f.visibility[i] : 1.0f;
      else if (name == "depth")
        v = hit ? g.depth[i] : kNaN;
      else if (name == "budget")
        v = f.maps.rays[i];
      else if (name == "quality")
        v = f.maps.quality[i];
      else if (name == "blend")
        v = f.maps.blend[i];
      else if (name == "eccentricity")
        v = f.maps.eccentricity[i];
      else if (name == "traced")
        v = f.ao_traced.empty() ? (hit ? f.maps.rays[i] : 0) : f.ao_traced[i];  // rays traced this frame
      else {
        std::string known;
        for (const auto& n : aov_names()) known += (known.empty() ? "" : ", ") + n;
        fail("aov: unknown buffer '{}' (known: {})", name, known);
      }
      image.at(x, y) = v;
    }
  return image;
}

void write_aovs(const Frame& frame, const std::string& spec) {
  std::stringstream stream(spec);
  std::string item;
  while (std::getline(stream, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == item.size()) fail("aov: expected NAME=FILE[,NAME=FILE…], got '{}'", item);
    const std::string name = item.substr(0, eq), path = item.substr(eq + 1);
    const std::string ext = std::filesystem::path(path).extension().string();
    if (ext != ".pfm" && ext != ".exr") fail("aov: {}: float buffers are written as .pfm or .exr", path);
    save_image(aov_image(frame, name), path);
  }
}

Image budget_mask(const Frame& f, int max_rays) {
  const int w = f.maps.width, h = f.maps.height;
  Image image(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float v = max_rays > 0 ? f.maps.rays[static_cast<size_t>(y) * w + x] / static_cast<float>(max_rays) : 0.0f;
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = v;
    }
  mark_gaze(image, f.gaze_px);
  return image;
}

void write_acuity_plot(const Display& display, const FoveationParams& params, const std::string& path) {
  Plot plot;
  plot.width = 740;
  const float left = 70, right = 650, top = 40, bottom = 380;
  const double e_max = 60.0, cpd_max = 45.0;
  auto px = [&](double e, double cpd) { return glm::vec2(left + (right - left) * e / e_max, bottom - (bottom - top) * cpd / cpd_max); };
  const double max_cpd = max_display_cpd(display);
  // Axes and ticks
  plot.strokes.push_back({{px(0, cpd_max), px(0, 0), px(e_max, 0)}, glm::vec3(0), 1.5f});
  for (int e = 0; e <= 60; e += 10) {
    plot.strokes.push_back({{px(e, 0), px(e, 0) + glm::vec2(0, 6)}, glm::vec3(0), 1});
    plot.labels.push_back({px(e, 0) + glm::vec2(0, 22), std::to_string(e), 13, true});
  }
  for (int c = 0; c <= 40; c += 10) {
    plot.strokes.push_back({{px(0, c), px(0, c) - glm::vec2(6, 0)}, glm::vec3(0), 1});
    plot.labels.push_back({px(0, c) - glm::vec2(34, -5), std::to_string(c), 13});
  }
  // Eq. 4 without and with the display's limit, and the AO budget on the right axis
  Stroke raw{{}, glm::vec3(0.2f, 0.4f, 0.9f), 1.5f, true}, clamped{{}, glm::vec3(0.1f), 2.5f}, budget{{}, glm::vec3(0.9f, 0.5f, 0.1f), 2};
  for (int i = 0; i <= 600; ++i) {
    const double e = e_max * i / 600.0;
    raw.points.push_back(px(e, kAcuityFovealCpd * kAcuityE2Deg / (kAcuityE2Deg + e)));
    const double fc = acuity_cutoff_cpd(e, max_cpd);
    clamped.points.push_back(px(e, fc));
    const double q = fc / acuity_cutoff_cpd(0, max_cpd);
    budget.points.push_back(px(e, cpd_max * ao_ray_budget(q, params) / std::max(1, params.max_rays)));
  }
  plot.strokes.push_back(raw);
  plot.strokes.push_back(clamped);
  plot.strokes.push_back(budget);
  plot.strokes.push_back({{px(0, max_cpd), px(e_max, max_cpd)}, glm::vec3(0.9f, 0.0f, 0.9f), 2});
  // Right axis: the AO budget, 0 … n_max
  plot.strokes.push_back({{px(e_max, cpd_max), px(e_max, 0)}, glm::vec3(0.9f, 0.5f, 0.1f), 1});
  plot.labels.push_back({px(e_max, cpd_max) + glm::vec2(6, 5), fmt::format("{} rays", params.max_rays), 12});
  plot.labels.push_back({px(e_max, 0) + glm::vec2(6, 5), "0 rays", 12});
  // Labels
  plot.labels.push_back({{(left + right) / 2, bottom + 48}, "eccentricity E [deg]", 15, true});
  plot.labels.push_back({{left - 60, top - 16}, "cut-off frequency f_c [cpd]", 15});
  // Legend: a swatch of each curve beside its label
  const float lx = right - 250;
  const std::pair<Stroke, std::string> legend[] = {
      {{{}, glm::vec3(0.9f, 0.0f, 0.9f), 2}, fmt::format("display limit {:.1f} cpd", max_cpd)},
      {{{}, glm::vec3(0.2f, 0.4f, 0.9f), 1.5f, true}, "eq. 4 without the limit"},
      {{{}, glm::vec3(0.1f), 2.5f}, "f_c(E), eq. 4 with the limit"},
      {{{}, glm::vec3(0.9f, 0.5f, 0.1f), 2}, fmt::format("AO rays n(E), right axis (gamma {:g})", params.gamma)}};
  float ly = top + 4;
  for (auto [stroke, text] : legend) {
    stroke.points = {{lx, ly - 4}, {lx + 12, ly - 4}, {lx + 24, ly - 4}};
    stroke.dashed = false;
    plot.strokes.push_back(stroke);
    plot.labels.push_back({{lx + 32, ly}, text, 13});
    ly += 20;
  }
  plot.labels.push_back({{left + 10, bottom + 64},
                         fmt::format("display {:g}x{:g} cm at {:g} cm, {}x{} px: {:.1f} x {:.1f} deg, {:.1f} px/deg", display.width_cm,
                                     display.height_cm, display.distance_cm, display.res_x, display.res_y, field_of_view_x_deg(display),
                                     field_of_view_y_deg(display), pixels_per_degree(display)),
                         12});
  plot.height = 460;
  save_plot(plot, path);
}

nlohmann::json frame_stats_json(const Frame& f, const RenderParams& p, const Scene& scene, size_t bvh_triangles, double build_ms,
                                int threads, const std::string& device, const std::string& trace_api) {
  const FrameStats& s = f.stats;
  nlohmann::json j;
  j["mode"] = to_string(p.mode);
  j["width"] = p.width;
  j["height"] = p.height;
  j["gaze_px"] = {f.gaze_px.x, f.gaze_px.y};
  j["seed"] = p.seed;
  j["threads"] = threads;
  j["device"] = device;
  j["scene"] = {
      {"source", scene.source}, {"triangles", bvh_triangles}, {"skipped_triangles", scene.skipped_triangles}, {"build_ms", build_ms}};
  j["rays"] = {
      {"primary", s.primary_rays}, {"ao", s.ao_rays}, {"shadow", s.shadow_rays}, {"total", s.primary_rays + s.ao_rays + s.shadow_rays}};
  j["ao_rays_per_pixel"] = {{"mean", s.ao_rays_mean}, {"min", s.ao_rays_min}, {"max", s.ao_rays_max}};
  j["time_ms"] = {{"primary", s.primary_ms}, {"foveation", s.foveation_ms}, {"ao", s.ao_ms}, {"shade", s.shade_ms}, {"total", s.total_ms}};
  j["ao_rays_per_second"] = s.ao_ms > 0 ? s.ao_rays / (s.ao_ms / 1000.0) : 0.0;
  j["model"] = {{"display_cm", {p.display.width_cm, p.display.height_cm}},
                {"distance_cm", p.display.distance_cm},
                {"display_px", {p.display.res_x, p.display.res_y}},
                {"pixels_per_degree", pixels_per_degree(p.display)},
                {"max_display_cpd", max_display_cpd(p.display)},
                {"ellipse_ratio", p.foveation.ellipse_ratio},
                {"max_rays", p.foveation.max_rays},
                {"min_rays", p.foveation.min_rays},
                {"gamma", p.foveation.gamma},
                {"beta", p.foveation.beta},
                {"ambient_constant", s.ambient_constant},
                {"ambient_constant_auto", !p.ambient_constant.has_value()}};
  j["ao_distance"] = std::isfinite(s.ao_distance) ? nlohmann::json(s.ao_distance) : nlohmann::json("inf");
  j["trace_api"] = trace_api;
  if (p.reuse.any())
    j["reuse"] = {{"adaptive", p.reuse.adaptive},
                  {"adaptive_min_rays", p.reuse.adaptive_min_rays},
                  {"denoise", p.reuse.denoise},
                  {"denoise_radius", p.reuse.denoise_radius},
                  {"temporal", p.reuse.temporal},
                  {"temporal_frames", p.reuse.temporal_frames},
                  {"history_frames", p.reuse.history_frames},
                  {"target_rays", p.reuse.target_rays},
                  {"tolerance", p.reuse.tolerance},
                  {"history_pixels", s.history_pixels},
                  {"denoised_pixels", s.denoised_pixels},
                  {"reuse_ms", s.reuse_ms}};
  j["peak_rss_mib"] = peak_rss_mib();
  return j;
}

Image scaled_nearest(const Image& image, int width, int height) {
  if (image.width == width && image.height == height) return image;
  if (image.empty() || width <= 0 || height <= 0) fail("scaled_nearest: {}x{} to {}x{}", image.width, image.height, width, height);
  Image out(width, height, image.channels);
  const cv::Mat from(image.height, image.width, CV_32FC(image.channels), const_cast<float*>(image.pixels.data()));
  cv::Mat to(height, width, CV_32FC(image.channels), out.pixels.data());
  cv::resize(from, to, to.size(), 0, 0, cv::INTER_NEAREST);
  return out;
}

void mark_gaze(Image& image, glm::dvec2 gaze_px) {
  const int w = image.width, h = image.height;
  const int gx = static_cast<int>(std::floor(gaze_px.x)), gy = static_cast<int>(std::floor(gaze_px.y));
  const int arm = std::max(4, std::min(w, h) / 40);
  for (int d = -arm; d <= arm; ++d)
    for (int t = -1; t <= 1; ++t)
      for (auto [x, y] : {std::pair{gx + d, gy + d + t}, std::pair{gx + d, gy - d + t}})
        if (x >= 0 && y >= 0 && x < w && y < h) {
          image.at(x, y, 0) = 1.0f;
          image.at(x, y, 1) = 0.0f;
          image.at(x, y, 2) = 0.0f;
        }
}

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // Linux reports KiB
}

void write_text_file(const std::string& path, const std::string& text) {
  check_not_an_input(path);
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) fail("{}: cannot write", path);
}

void write_json_file(const std::string& path, const nlohmann::json& json) { write_text_file(path, json.dump(2) + "\n"); }

}  // namespace foveal
