// foveal/gaze/summary.h — what `foveal gaze` reports about a recording: its samples and screen,
// the fixations each filter finds, and their agreement with the tracker's own events.
#pragma once

#include "foveal/gaze/fixation.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace foveal {

struct FilterSummary {
  FixationMethod method = FixationMethod::ivt;
  FixationResult result;
  double fixation_fraction = 0;  // valid samples labelled fixation
  double mean_duration_ms = 0;
  std::optional<Agreement> agreement;         // offline filter vs the tracker's fixations
  std::optional<Agreement> causal_agreement;  // the causal (live) version vs the tracker's fixations
};

struct GazeSummary {
  std::vector<FilterSummary> filters;  // ivt, idt
  nlohmann::json json;                 // the `gaze --json` document
};

// Per sample: whether the causal tracker was inside an established fixation after that sample.
std::vector<bool> causal_fixation_mask(const Recording& recording, FixationMethod method, const FixationParams& params,
                                       const GazeGeometry& geometry);

GazeSummary summarize_recording(const Recording& recording, const Display& display, const FixationParams& params);

// The human-readable summary (several lines, ending with a newline).
std::string format_summary(const Recording& recording, const GazeSummary& summary);

}  // namespace foveal
