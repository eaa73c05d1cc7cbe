// Micro-benchmarks: the renderer's AO pass against raw Embree occlusion queries on the same rays.
//   build/bench/foveal_microbench [--benchmark_filter=...]
// Both report items/s = AO rays per second on builtin:box, 320×200, 64 rays per pixel.
#include "foveal/render/render.h"

#include <benchmark/benchmark.h>

using namespace foveal;

namespace {

struct Setup {
  Scene scene = make_builtin_scene("box");
  Tracer tracer{scene};
  RenderParams params;
  GBuffer gbuffer;
  FoveationMaps maps;
  std::vector<Ray> rays;
  float ao_distance = 0, epsilon = 0;  // resolved once, outside the timed loops
  Setup() {
    params.width = 320;
    params.height = 200;
    params.mode = RenderMode::full;
    params.foveation.max_rays = 64;
    gbuffer = trace_primary(tracer, scene, scene.cameras.front(), params.width, params.height);
    maps = foveation_maps(params, {160, 100});
    ao_distance = resolve_ao_distance(scene, scene.bounds(), {});
    epsilon = surface_epsilon(scene.bounds());
    collect_ao_rays(gbuffer, maps, ao_distance, epsilon, 1, 1, rays);
  }
};

Setup& setup() {
  static Setup s;
  return s;
}

// The renderer's AO pass: ray generation, tracing and counting.
void BM_RendererAoPass(benchmark::State& state) {
  Setup& s = setup();
  s.tracer.set_occlusion_api(static_cast<TraceApi>(state.range(0)));
  std::vector<float> visibility;
  uint64_t rays = 0;
  for (auto _ : state) rays += trace_ao(s.tracer, s.gbuffer, s.maps, s.ao_distance, s.epsilon, 1, visibility);
  state.SetItemsProcessed(static_cast<int64_t>(rays));
  state.SetLabel(to_string(static_cast<TraceApi>(state.range(0))));
}

// Raw Embree occlusion on the same rays, converted before timing.
void BM_RawEmbreeOcclusion(benchmark::State& state) {
  Setup& s = setup();
  const auto api = static_cast<TraceApi>(state.range(0));
  for (auto _ : state) {
    const RawTraceResult r = measure_raw_occlusion(s.tracer, s.rays, api);
    state.SetIterationTime(r.seconds);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * s.rays.size()));
  state.SetLabel(to_string(api));
}

}  // namespace

BENCHMARK(BM_RendererAoPass)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RawEmbreeOcclusion)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseManualTime();
