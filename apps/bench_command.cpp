// apps/bench_command.cpp — `foveal bench ao`: the first paper's Table 1 on this machine.
#include "commands.h"
#include "foveal/cuda/gpu.h"
#include "foveal/experiments/gpu_benchmark.h"
#include "foveal/render/outputs.h"
#include "foveal/experiments/ao_benchmark.h"
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
int run_bench_ao(const BenchAoOptions& o) {
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
  validate(p.render);
  if (device == ComputeDevice::cuda) {
    // The GPU table, with the CPU measured in the same run
    gpu::BenchParams g;
    g.render = p.render;
    g.cameras = p.cameras;
    g.repeats = o.full ? 20 : 5;
    g.cpu_repeats = p.repeats;
    fmt::print("foveal bench ao: {}, {}x{}, n_max {}, gamma {:g}; GPU {} frames per case (median), CPU {} ({} threads)\n", spec, size.x,
               size.y, o.max_rays, o.gamma, g.repeats, g.cpu_repeats, threads.threads());
    const gpu::BenchResult result =
        gpu::run_benchmark(scene, g, [](const std::string& line) { fmt::print("  {}\n", line), std::fflush(stdout); });
    const std::string table = gpu::to_markdown(result);
    fmt::print("\n{}", table);
    if (!o.json.empty()) write_json_file(o.json, gpu::to_json(result));
    if (!o.markdown.empty()) write_text_file(o.markdown, table);
    return 0;
  }
  const Tracer tracer(scene, parse_trace_api(o.trace_api));
  fmt::print("foveal bench ao: {} ({} triangles), {}x{}, n_max {}, gamma {:g}, {} threads, {} frame(s) per case\n", spec,
             tracer.triangles(), size.x, size.y, o.max_rays, o.gamma, threads.threads(), p.repeats);
  const AoBenchResult result =
      run_ao_benchmark(scene, tracer, p, [](const std::string& line) { fmt::print("  {}\n", line), std::fflush(stdout); });
  const std::string table = to_markdown(result);
  fmt::print("\n{}", table);
  if (!o.json.empty()) {
    auto j = to_json(result);
    j["repeats"] = p.repeats;
    write_json_file(o.json, j);
  }
  if (!o.markdown.empty()) write_text_file(o.markdown, table);
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
  ao->add_option("--json", o->json, "write the table as JSON");
  ao->add_option("--markdown", o->markdown, "write the table as Markdown");

  auto vision = add_bench_vision_command(*bench);
  auto blur = add_bench_blur_command(*bench);
  auto quality = add_bench_quality_command(*bench);
  auto* blur_cmd = bench->get_subcommand("blur");
  auto* quality_cmd = bench->get_subcommand("quality");
  auto run_ao = [o] { return run_bench_ao(*o); };
  return [run_ao, vision, blur, quality, ao, blur_cmd, quality_cmd] {
    return ao->parsed() ? run_ao() : blur_cmd->parsed() ? blur() : quality_cmd->parsed() ? quality() : vision();
  };
}

}  // namespace foveal::app
