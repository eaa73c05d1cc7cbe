// Micro-benchmarks: the impairment passes at 1280×720 (3 channels, linear), each against a
// baseline of the same run — one Gaussian blur of the image by OpenCV (σ = 2 px), a whole-image
// operation of the same size.
//   build/bench/foveal_microbench --benchmark_filter=Impair
#include "foveal/impair/impairments.h"
#include "foveal/impair/profile.h"

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

using namespace foveal;

namespace {

Image impair_picture() {
  Image img(1280, 720, 3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 0.5f + 0.4f * std::sin(0.05f * x * (c + 1) + 0.03f * y) * std::cos(0.07f * y);
  return img;
}

Retinotopy retinotopy() {
  Retinotopy r{1280, 720, std::vector<glm::vec2>(1280 * 720), 30.0};
  for (int y = 0; y < 720; ++y)
    for (int x = 0; x < 1280; ++x) r.field_deg[size_t(y) * 1280 + x] = glm::vec2((x - 600) / 30.0f, (340 - y) / 30.0f);
  return r;
}

void BM_ImpairBaselineGaussian(benchmark::State& state) {
  static Image img = impair_picture();
  cv::Mat in(img.height, img.width, CV_32FC3, img.pixels.data()), out;
  for (auto _ : state) {
    cv::GaussianBlur(in, out, cv::Size(0, 0), 2.0);
    benchmark::DoNotOptimize(out.data);
  }
}
BENCHMARK(BM_ImpairBaselineGaussian)->Unit(benchmark::kMillisecond);

void run(benchmark::State& state, const std::string& spec) {
  static const Image img = impair_picture();
  static const Retinotopy r = retinotopy();
  const ImpairmentPasses passes(parse_eye_spec(spec).impair);
  for (auto _ : state) {
    Image copy = img;
    passes.apply(copy, r);
    benchmark::DoNotOptimize(copy.pixels.data());
  }
}

void BM_ImpairGlare(benchmark::State& state) { run(state, "cataract:0.5"); }
void BM_ImpairFieldContrast(benchmark::State& state) { run(state, "field:arcuate:20"); }
void BM_ImpairFieldFill(benchmark::State& state) { run(state, "field:arcuate:20+field-mode:fill"); }
void BM_ImpairMetamorphopsia(benchmark::State& state) { run(state, "metamorphopsia:0.3"); }
void BM_ImpairColour(benchmark::State& state) { run(state, "cvd:deutan:0.6"); }
void BM_ImpairAll(benchmark::State& state) { run(state, "cataract:0.5+field:arcuate:20+metamorphopsia:0.3+cvd:deutan:0.6"); }
BENCHMARK(BM_ImpairGlare)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ImpairFieldContrast)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ImpairFieldFill)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ImpairMetamorphopsia)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ImpairColour)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ImpairAll)->Unit(benchmark::kMillisecond);

}  // namespace
