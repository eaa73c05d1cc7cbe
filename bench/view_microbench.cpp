// Micro-benchmarks of the viewer's per-frame work at 840×525: a new image to display bytes (the
// sRGB table against a pow per channel, the baseline it replaced) and the region overlays
// (contours + AO heat map, redrawn once per new fixation) against evaluating the foveation model
// exactly at every pixel (the baseline they approximate).
//   build/bench/foveal_microbench --benchmark_filter='Srgb|Overlays|Foveation'
#include "foveal/io/image_io.h"
#include "foveal/ui/overlays.h"

#include <benchmark/benchmark.h>
#include <tbb/parallel_for.h>

#include <cmath>

using namespace foveal;

namespace {

constexpr int kW = 840, kH = 525;

Image frame() {
  Image img(kW, kH, 3);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 0.5f + 0.5f * std::sin(0.05f * x * (c + 1) + 0.03f * y);
  return img;
}

void BM_SrgbPowPerChannel(benchmark::State& state) {
  static const Image img = frame();
  Rgba8 out(kW, kH);
  for (auto _ : state) {
    tbb::parallel_for(0, kH, [&](int y) {
      for (int x = 0; x < kW; ++x)
        for (int k = 0; k < 3; ++k) out.at(x, y)[k] = static_cast<uint8_t>(std::lround(linear_to_srgb(img.at(x, y, k)) * 255.0f));
    });
    benchmark::DoNotOptimize(out.px.data());
  }
}

void BM_SrgbTable(benchmark::State& state) {
  static const Image img = frame();
  for (auto _ : state) benchmark::DoNotOptimize(to_rgba8(img));
}

void BM_FoveationExactPerPixel(benchmark::State& state) {
  const FoveationModel model(Display{}, kW, kH, {400, 300}, FoveationParams{});
  std::vector<float> q(size_t(kW) * kH);
  for (auto _ : state) {
    tbb::parallel_for(0, kH, [&](int y) {
      for (int x = 0; x < kW; ++x) q[size_t(y) * kW + x] = static_cast<float>(model.evaluate(x, y).quality);
    });
    benchmark::DoNotOptimize(q.data());
  }
}

void BM_RegionOverlays(benchmark::State& state) {
  const FoveationModel model(Display{}, kW, kH, {400, 300}, FoveationParams{});
  OverlayInputs in;
  in.model = &model;
  const Overlays which = parse_overlays("contours,budget");
  Rgba8 image(kW, kH);
  for (auto _ : state) {
    draw_overlays(image, 0, 0, kW, kH, which, in);
    benchmark::DoNotOptimize(image.px.data());
  }
}

}  // namespace

BENCHMARK(BM_SrgbPowPerChannel)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SrgbTable)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FoveationExactPerPixel)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RegionOverlays)->Unit(benchmark::kMillisecond)->UseRealTime();
