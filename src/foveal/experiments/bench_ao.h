// foveal/experiments/bench_ao.h — `bench ao` on any device through one call: the first paper's
// Table 1 measured by the device's table (ao_benchmark.h: the CPU's with Embree's raw rates;
// gpu_benchmark.h: the GPU's, with the CPU measured in the same run), both run by the one
// harness run_ao_table, reported as Markdown and JSON.
#pragma once

#include "foveal/experiments/ao_benchmark.h"
#include "foveal/util/device.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>

namespace foveal {

struct AoTableRun {
  AoBenchParams params;                   // size, model, cameras; params.repeats: the CPU's frames per case (median)
  TraceApi trace_api = TraceApi::stream;  // how the CPU renderer hands occlusion rays to Embree
  int gpu_repeats = 5;                    // the GPU's frames per case (median)
  std::string scene_name;                 // as the user named it (the header line)
  int threads = 0;                        // the CPU's worker threads (the header line)
};

struct AoTableReport {
  std::string markdown;
  nlohmann::json json;
};

// Runs the table on `device`; `say` receives the header line first, then one line per finished
// measurement.
AoTableReport run_bench_ao(const Scene& scene, ComputeDevice device, const AoTableRun& run,
                           const std::function<void(const std::string&)>& say);

}  // namespace foveal
