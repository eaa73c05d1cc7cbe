// libFuzzer target: Pupil's gaze_positions.csv, fixations.csv and blinks.csv readers (the first
// byte picks which) must turn any bytes into data or an Error.
#include "fuzz_recording.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    switch (data[0] % 3) {
      case 0:
        fuzz_recording(data + 1, size - 1, foveal::GazeFormat::pupil, "gaze_positions.csv");
        break;
      case 1:
        foveal::parse_pupil_fixations(text, "fixations.csv", {640, 480});
        break;
      default:
        foveal::parse_pupil_blinks(text, "blinks.csv");
        break;
    }
  } catch (const foveal::Error&) {}
  return 0;
}
