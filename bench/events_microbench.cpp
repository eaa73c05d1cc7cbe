// Micro-benchmarks: the event detectors, in samples per second on one core (the aim for the
// recommended detector: at least 10^7). Each detector runs on the same recording as a baseline of
// the same run: I-VT, the simplest pass over the samples.
//   build/bench/foveal_microbench --benchmark_filter=Events
// Recordings: IRF S1 (81,003 samples at 1000 Hz, Zemblys et al. 2018) where ../shared/data sits
// beside the repository, and always a synthetic minute of free viewing with pursuit at 1000 Hz
// (gaze/synthetic.h: 0.05° RMS noise, 5 % of the samples lost in bursts).
#include "foveal/gaze/detect.h"
#include "foveal/gaze/fixation.h"
#include "foveal/gaze/recording.h"
#include "foveal/gaze/synthetic.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <optional>
#include <string>

using namespace foveal;

namespace {

struct EventsInput {
  Recording recording;
  Display display;
};

const EventsInput* irf_s1() {
  static const std::optional<EventsInput> input = []() -> std::optional<EventsInput> {
    const std::string path = std::string(FOVEAL_DATA_DIR) + "/eye-movements/irf/lookAtPoint_EL_S1.csv";
    if (!std::filesystem::exists(path)) return std::nullopt;
    const Display display{53.3, 30.1, 56.5, 1920, 1080};
    ReadOptions read;
    read.screen_px = {display.res_x, display.res_y};
    read.screen_from_user = true;
    read.display_width_cm = display.width_cm;
    read.display_height_cm = display.height_cm;
    read.display_distance_cm = display.distance_cm;
    return EventsInput{read_recording(path, read), display};
  }();
  return input ? &*input : nullptr;
}

const EventsInput* synthetic_minute() {
  static const EventsInput input = [] {
    SyntheticSignal::Degradation degradation;
    degradation.loss_fraction = 0.05;
    return EventsInput{synthetic_viewing(60, 1000, true, 11).recording(degradation), synthetic_display()};
  }();
  return &input;
}

void detect(benchmark::State& state, const EventsInput* input, EventMethod method) {
  if (!input) {
    state.SkipWithError("skipped: ../shared/data/eye-movements/irf is absent");
    return;
  }
  const GazeGeometry geometry(input->display, input->recording.screen_px);
  for (auto _ : state) {
    EventDetection d = detect_events(input->recording, geometry, method, EventParams{}, FixationParams{});
    benchmark::DoNotOptimize(d.labels.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(input->recording.samples.size()));
}

void BM_EventsIrfIvt(benchmark::State& state) { detect(state, irf_s1(), EventMethod::ivt); }
void BM_EventsIrfNhr(benchmark::State& state) { detect(state, irf_s1(), EventMethod::nhr); }
void BM_EventsIrfNh(benchmark::State& state) { detect(state, irf_s1(), EventMethod::nh); }
void BM_EventsSyntheticIvt(benchmark::State& state) { detect(state, synthetic_minute(), EventMethod::ivt); }
void BM_EventsSyntheticNhr(benchmark::State& state) { detect(state, synthetic_minute(), EventMethod::nhr); }
BENCHMARK(BM_EventsIrfIvt)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EventsIrfNhr)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EventsIrfNh)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EventsSyntheticIvt)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EventsSyntheticNhr)->Unit(benchmark::kMillisecond);

}  // namespace
