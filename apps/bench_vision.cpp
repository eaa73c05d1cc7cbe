// apps/bench_vision.cpp — `foveal bench vision`: the second paper's Table 1 (per-stage times of
// one simulation step) on this machine.
#include "commands.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/vision/simulate.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>

namespace foveal::app {

namespace {

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

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
      for (const std::string& dir : {std::string("scenes"), std::string(FOVEAL_SOURCE_DIR) + "/scenes"}) {
        const std::string conference = dir + "/conference.json";
        if (std::filesystem::exists(conference) && std::filesystem::exists(std::string(FOVEAL_SOURCE_DIR) + "/../shared/data/scenes/conference/conference.obj")) {
          scenes.push_back(conference);
          break;
        }
      }
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
        p.display.res_x = size.x;
        p.display.res_y = size.y;
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
        const double t = median_of(trace), f = median_of(features), sh = median_of(sharpness), b = median_of(blur),
                     all = median_of(total);
        const double ratio = t > 0 ? (f + sh + b) / t : 0;
        fmt::print("  {:<28} {:>9}  trace {:6.1f}  features {:6.1f}  sharpness {:6.1f}  blur {:6.1f}  total {:6.1f} ms  (rest/trace {:.2f})\n",
                   scene.source, size_text, t, f, sh, b, all, ratio);
        md += fmt::format("| {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.2f} |\n", scene.source, size_text, t, f, sh, b, all, ratio);
        rows.push_back({{"scene", scene.source}, {"triangles", tracer.triangles()}, {"size", size_text}, {"steps", o->steps - 1},
                        {"time_ms", {{"trace", t}, {"features", f}, {"sharpness", sh}, {"blur", b}, {"total", all}}},
                        {"non_tracing_over_trace", ratio}});
      }
    }
    if (!o->json.empty()) {
      std::ofstream out(o->json);
      out << nlohmann::json({{"threads", threads.threads()}, {"eye", o->eye}, {"rows", rows}}).dump(2) << "\n";
      if (!out) fail("{}: cannot write", o->json);
    }
    if (!o->markdown.empty()) {
      std::ofstream out(o->markdown);
      out << md;
      if (!out) fail("{}: cannot write", o->markdown);
    }
    return 0;
  };
}

}  // namespace foveal::app
