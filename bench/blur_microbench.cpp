// Micro-benchmarks: the per-pixel variable blur against OpenCV's separable Gaussian of the same σ
// (the fastest way to blur a whole image by one σ, and so the baseline for a blur whose kernel
// differs per pixel). 1024×768, 3 channels, a constant CoC diameter d (σ = d/6).
//   build/bench/foveal_microbench --benchmark_filter=Blur
#include "foveal/util/memory.h"
#include "foveal/vision/blur.h"

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

using namespace foveal;

namespace {

Image blur_picture() {
  Image img(1024, 768, 3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 0.5f + 0.5f * std::sin(0.05f * x * (c + 1) + 0.03f * y) * std::cos(0.07f * y);
  return img;
}

// Arguments: CoC diameter in pixels, scatter-aware (1) or not (0)
void BM_VariableBlur(benchmark::State& state) {
  static const Image img = blur_picture();
  const std::vector<float> coc(size_t(img.width) * img.height, float(state.range(0)));
  BlurParams p;
  p.scatter_aware = state.range(1) != 0;
  for (auto _ : state) benchmark::DoNotOptimize(variable_blur(img, coc, p));
  state.SetItemsProcessed(state.iterations() * img.width * img.height);
}

void BM_OpenCvGaussian(benchmark::State& state) {
  static const Image img = blur_picture();
  const cv::Mat src(img.height, img.width, CV_32FC3, const_cast<float*>(img.pixels.data()));
  cv::Mat dst;
  const double sigma = state.range(0) / 6.0;
  for (auto _ : state) {
    cv::GaussianBlur(src, dst, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    benchmark::DoNotOptimize(dst.data);
  }
  state.SetItemsProcessed(state.iterations() * img.width * img.height);
}

}  // namespace

BENCHMARK(BM_VariableBlur)->ArgsProduct({{4, 8, 16, 32}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OpenCvGaussian)->Arg(4)->Arg(8)->Arg(16)->Arg(32)->Unit(benchmark::kMillisecond)->UseRealTime();
int main(int argc, char** argv) {
  foveal::keep_freed_memory();  // as the foveal executable does
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
