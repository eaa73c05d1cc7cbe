// fuzz/fuzz_recording.h — shared body of the recording fuzz targets: parse with one reader, and
// when that succeeds, run every fixation filter (offline and causal), the summary and every event detector (with its
// events table) over what it read.
#pragma once

#include "foveal/gaze/detect.h"
#include "foveal/gaze/summary.h"
#include "foveal/util/error.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

inline void fuzz_recording(const uint8_t* data, size_t size, foveal::GazeFormat format, const char* name) {
  foveal::ReadOptions options;
  options.format = format;
  options.screen_px = {640, 480};
  try {
    const foveal::Recording r = foveal::parse_recording(std::string(reinterpret_cast<const char*>(data), size), name, options);
    if (r.screen_px.x < 1 || r.screen_px.y < 1) return;
    const foveal::Display display{47.5, 30, 60, r.screen_px.x, r.screen_px.y};
    const foveal::GazeSummary s = foveal::summarize_recording(r, display, {});
    (void)foveal::format_summary(r, s);
    const foveal::GazeGeometry geometry(display, r.screen_px);
    for (foveal::FixationMethod m : {foveal::FixationMethod::mean, foveal::FixationMethod::ivt, foveal::FixationMethod::idt,
                                     foveal::FixationMethod::ivvt}) {  // the causal filters, as replay and the viewer run them
      foveal::FixationTracker tracker(m, {}, geometry);
      for (const foveal::GazeSample& sample : r.samples) {
        tracker.push(sample);
        if (const auto g = tracker.current(); g && !(std::isfinite(g->x) && std::isfinite(g->y))) __builtin_trap();
      }
    }
    for (foveal::EventMethod m : {foveal::EventMethod::ivt, foveal::EventMethod::idt, foveal::EventMethod::ivvt, foveal::EventMethod::ek,
                                  foveal::EventMethod::nh, foveal::EventMethod::nhp, foveal::EventMethod::nhr}) {
      const foveal::EventDetection d = foveal::detect_events(r, geometry, m, {}, {});
      if (d.labels.size() != r.samples.size()) __builtin_trap();
      (void)foveal::events_tsv(d, r);
    }
  } catch (const foveal::Error&) {}
}
