// libFuzzer target: the BIDS eye-tracking reader must turn any sidecar and TSV (and physioevents)
// into a recording or an Error, and the detectors must cope with what it reads. The input is the
// sidecar JSON, a NUL byte, the physio TSV, and optionally a NUL, the physioevents sidecar, a NUL
// and its TSV.
#include "foveal/gaze/bids.h"
#include "foveal/gaze/summary.h"
#include "foveal/util/error.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> parts;
  for (size_t from = 0;;) {
    const size_t nul = bytes.find('\0', from);
    parts.push_back(bytes.substr(from, nul == std::string::npos ? std::string::npos : nul - from));
    if (nul == std::string::npos || parts.size() == 4) break;
    from = nul + 1;
  }
  if (parts.size() < 2) return 0;
  const nlohmann::json side = nlohmann::json::parse(parts[0], nullptr, false);
  if (side.is_discarded()) return 0;
  foveal::BidsFiles files;
  files.physio = "fuzz_physio.tsv.gz";
  files.sidecar = "fuzz_physio.json";
  if (parts.size() == 4) {
    files.events_json = nlohmann::json::parse(parts[2], nullptr, false);
    if (files.events_json.is_discarded()) return 0;
    files.events_name = "fuzz_physioevents.tsv.gz";
    files.events_sidecar = "fuzz_physioevents.json";
    files.events_tsv = parts[3];
  }
  foveal::ReadOptions options;
  options.screen_px = {640, 480};
  try {
    const foveal::Recording r = foveal::parse_bids_physio(parts[1], side, files, options);
    if (r.screen_px.x < 1 || r.screen_px.y < 1 || r.screen_px.x > 100000 || r.screen_px.y > 100000) return 0;
    const foveal::Display display{47.5, 30, 60, r.screen_px.x, r.screen_px.y};
    (void)foveal::summarize_recording(r, display, {});
    const foveal::GazeGeometry geometry(display, r.screen_px);
    (void)foveal::detect_events(r, geometry, foveal::EventMethod::nhr, {}, {});
  } catch (const foveal::Error&) {}
  return 0;
}
