// libFuzzer target: the expert-label reader must turn any bytes into labels or an Error, the
// labels must evaluate against themselves (and a shifted copy) without fault, and putting them on
// a recording's samples by time (align_labels: 1 kHz samples from 0 s, and the labels' own times)
// must give one label per sample or an Error.
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
    for (const std::vector<double>& samples : {f.t_s, [] {
                                                 std::vector<double> t(2000);
                                                 for (size_t i = 0; i < t.size(); ++i) t[i] = 0.001 * i;
                                                 return t;
                                               }()}) {
      try {
        const foveal::AlignedLabels a = foveal::align_labels(f, samples);
        if (a.label.size() != samples.size() || a.covered.size() != samples.size() || a.count > samples.size()) __builtin_trap();
        (void)foveal::evaluate_labels(a.label, a.label, samples, a.covered);
      } catch (const foveal::Error&) {}
    }
  } catch (const foveal::Error&) {}
  return 0;
}
