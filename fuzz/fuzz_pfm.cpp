// libFuzzer target: the PFM reader must turn any bytes into an image or an Error.
#include "foveal/io/image_io.h"
#include "foveal/util/error.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    foveal::parse_pfm(std::string(reinterpret_cast<const char*>(data), size), "fuzz.pfm");
  } catch (const foveal::Error&) {}
  return 0;
}
