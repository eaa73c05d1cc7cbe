// libFuzzer target: the csv reader must turn any bytes into a recording or an Error, and the
// fixation filters must cope with whatever it reads.
#include "fuzz_recording.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz_recording(data, size, foveal::GazeFormat::csv, "fuzz.csv");
  return 0;
}
