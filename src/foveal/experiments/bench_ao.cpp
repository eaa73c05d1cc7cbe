// foveal/experiments/bench_ao.cpp — see bench_ao.h.
#include "foveal/experiments/bench_ao.h"

#include "foveal/experiments/gpu_benchmark.h"
#include "foveal/trace/tracer.h"

#include <fmt/format.h>

namespace foveal {

AoTableReport run_bench_ao(const Scene& scene, ComputeDevice device, const AoTableRun& run,
                           const std::function<void(const std::string&)>& say) {
  const RenderParams& r = run.params.render;
  validate(r);
  AoTableReport report;
  if (device == ComputeDevice::cuda) {
    gpu::BenchParams g;  // the GPU's table, with the CPU measured in the same run
    g.render = r;
    g.cameras = run.params.cameras;
    g.repeats = run.gpu_repeats;
    g.cpu_repeats = run.params.repeats;
    say(fmt::format("foveal bench ao: {}, {}x{}, n_max {}, gamma {:g}; GPU {} frames per case (median), CPU {} ({} threads)",
                    run.scene_name, r.width, r.height, r.foveation.max_rays, r.foveation.gamma, g.repeats, g.cpu_repeats, run.threads));
    const gpu::BenchResult result = gpu::run_benchmark(scene, g, [&](const std::string& line) { say("  " + line); });
    report.markdown = gpu::to_markdown(result);
    report.json = gpu::to_json(result);
    return report;
  }
  const Tracer tracer(scene, run.trace_api);
  say(fmt::format("foveal bench ao: {} ({} triangles), {}x{}, n_max {}, gamma {:g}, {} threads, {} frame(s) per case", run.scene_name,
                  tracer.triangles(), r.width, r.height, r.foveation.max_rays, r.foveation.gamma, run.threads, run.params.repeats));
  const AoBenchResult result = run_ao_benchmark(scene, tracer, run.params, [&](const std::string& line) { say("  " + line); });
  report.markdown = to_markdown(result);
  report.json = to_json(result);
  report.json["repeats"] = run.params.repeats;
  return report;
}

}  // namespace foveal
