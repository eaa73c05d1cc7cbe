// libFuzzer target: eye profiles (JSON) must give an eye or an Error naming the JSON path. Field
// files are looked up in a folder that does not exist, so only generated defects load.
#include "foveal/impair/profile.h"
#include "foveal/util/error.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    foveal::parse_eye_profile(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json", "/nonexistent-foveal-fuzz");
  } catch (const foveal::Error&) {}
  return 0;
}
