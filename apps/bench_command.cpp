// apps/bench_command.cpp — `foveal bench ao`: the first paper's Table 1 on this machine.
#include "commands.h"
#include "foveal/experiments/bench_ao.h"
#include "foveal/render/outputs.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"

#include <fmt/core.h>

#include <filesystem>
#include <memory>

namespace foveal::app {

std::string repository_scene(const std::string& file, const std::string& data_file) {
  const std::string data = std::string(FOVEAL_SOURCE_DIR) + "/../shared/data/";
  if (!data_file.empty() && !std::filesystem::exists(data + data_file)) return "";
  for (const std::string& dir : {std::string("scenes"), std::string(FOVEAL_SOURCE_DIR) + "/scenes"})
    if (std::filesystem::exists(dir + "/" + file)) return dir + "/" + file;
  return "";
}

Scene load_paper_scene(std::string& spec, const std::string& command) {
  if (!spec.empty()) return load_scene(spec);
  // The paper's dragon box, or the built-in box when the dragon is missing
  spec = repository_scene("dragon-box.json");
  try {
    if (spec.empty()) fail("scenes/dragon-box.json not found");
    return load_scene(spec);
  } catch (const Error& e) {
    fmt::print("foveal {}: the paper's dragon scene is unavailable ({}); running on builtin:box instead\n", command, e.what());
    spec = "builtin:box";
    return load_scene(spec);
  }
}

namespace {

// bench ao's options as typed.
struct BenchAoOptions {
  std::string scene, size = "840x525", display = "47.5,30,60,1680,1050", json, markdown, trace_api = "stream", device = "auto";
  std::vector<std::string> cameras;
  int max_rays = 400, threads = 0, repeats = 1;
  double gamma = 2;
  uint64_t seed = 1;
  bool full = false;
};

// The first paper's Table 1 on the chosen device (on the GPU with the CPU measured in the same run).
int run_bench_ao_command(const BenchAoOptions& o) {
  const ThreadScope threads(o.threads);
  std::string spec = o.scene;
  const Scene scene = load_paper_scene(spec, "bench ao");
  const ComputeDevice device = choose_device(o.device);
  fmt::print("foveal bench ao: device {}\n", describe_device(device));
  AoBenchParams p;
  const glm::ivec2 size = parse_size("--size", o.size);
  p.render.width = size.x;
  p.render.height = size.y;
  p.render.display = resolve_display(o.display, size);
  p.render.foveation.max_rays = o.max_rays;
  p.render.foveation.gamma = o.gamma;
  p.render.seed = o.seed;
  p.cameras = o.cameras;
  p.repeats = o.full ? std::max(o.repeats, 5) : o.repeats;
  // The table on the chosen device (on the GPU, the CPU measured in the same run)
  AoTableRun run;
  run.params = p;
  run.trace_api = parse_trace_api(o.trace_api);
  run.gpu_repeats = o.full ? 20 : 5;
  run.scene_name = spec;
  run.threads = threads.threads();
  const AoTableReport report = run_bench_ao(scene, device, run, [](const std::string& line) {
    fmt::print("{}\n", line);
    std::fflush(stdout);
  });
  fmt::print("\n{}", report.markdown);
  if (!o.json.empty()) write_json_file(o.json, report.json);
  if (!o.markdown.empty()) write_text_file(o.markdown, report.markdown);
  return 0;
}

}  // namespace

std::function<int()> add_bench_command(CLI::App& app) {
  auto* bench = app.add_subcommand("bench", "benchmarks that reproduce the papers' tables");
  bench->require_subcommand(1);
  auto* ao = bench->add_subcommand("ao", "the first paper's Table 1: full-frame vs foveated AO for 3 cameras × 6 gaze points");

  auto o = std::make_shared<BenchAoOptions>();
  ao->add_option("--scene", o->scene,
                 "scene (default: scenes/dragon-box.json, the paper's dragon in a box; builtin:box when the dragon is absent)");
  ao->add_option("--camera", o->cameras, "camera names to measure (default: all of the scene's)")->delimiter(',');
  ao->add_option("--size", o->size, "render size WxH")->capture_default_str();
  ao->add_option("--display", o->display, "display W_CM,H_CM,DIST_CM[,RES_X,RES_Y]")->capture_default_str();
  ao->add_option("--max-rays", o->max_rays, "n_max")->capture_default_str();
  ao->add_option("--gamma", o->gamma, "γ of the ray budget")->capture_default_str();
  ao->add_option("--seed", o->seed, "seed")->capture_default_str();
  ao->add_option("--repeats", o->repeats, "frames per case (median reported)")->capture_default_str()->check(CLI::Range(1, 100));
  ao->add_flag("--full", o->full, "full run: 5 frames per case (default: 1, for a quick look)");
  ao->add_option("--threads", o->threads, "worker threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
  ao->add_option("--trace-api", o->trace_api, "occlusion API of the renderer: stream, packet8 or single")->capture_default_str();
  add_device_option(*ao, o->device);
  ao->add_option("--json", o->json, "write the table as JSON")->check(output_file());
  ao->add_option("--markdown", o->markdown, "write the table as Markdown")->check(output_file());

  auto vision = add_bench_vision_command(*bench);
  auto blur = add_bench_blur_command(*bench);
  auto quality = add_bench_quality_command(*bench);
  auto latency = add_bench_latency_command(*bench);
  auto events = add_bench_events_command(*bench);
  auto stalls = add_bench_stalls_command(*bench);
  auto* events_cmd = bench->get_subcommand("events");
  auto* stalls_cmd = bench->get_subcommand("stalls");
  auto* blur_cmd = bench->get_subcommand("blur");
  auto* quality_cmd = bench->get_subcommand("quality");
  auto* latency_cmd = bench->get_subcommand("latency");
  auto run_ao = [o] { return run_bench_ao_command(*o); };
  return [run_ao, vision, blur, quality, latency, events, stalls, ao, blur_cmd, quality_cmd, latency_cmd, events_cmd, stalls_cmd] {
    if (latency_cmd->parsed()) return latency();
    if (stalls_cmd->parsed()) return stalls();
    if (events_cmd->parsed()) return events();
    return ao->parsed() ? run_ao() : blur_cmd->parsed() ? blur() : quality_cmd->parsed() ? quality() : vision();
  };
}

}  // namespace foveal::app
