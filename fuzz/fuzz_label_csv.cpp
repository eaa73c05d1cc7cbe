// libFuzzer target: the expert-label reader must turn any bytes into labels or an Error, and the
// labels must evaluate against themselves (and a shifted copy) without fault.
#include "foveal/gaze/events.h"
#include "foveal/util/error.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const foveal::LabelFile f = foveal::parse_label_file(std::string(reinterpret_cast<const char*>(data), size), "fuzz.csv");
    (void)foveal::evaluate_labels(f.label, f.label, f.t_s);
    std::vector<foveal::EventLabel> shifted(f.label.begin() + 1, f.label.end());
    shifted.push_back(foveal::EventLabel::undefined);
    (void)foveal::evaluate_labels(shifted, f.label, f.t_s);
  } catch (const foveal::Error&) {}
  return 0;
}
