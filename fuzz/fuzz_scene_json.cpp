// libFuzzer target: the scene JSON parser must turn any bytes into a scene or an Error.
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    // Mesh files are looked up in a folder that does not exist, so only shapes can load
    foveal::parse_scene_json(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json", "/nonexistent-foveal-fuzz");
  } catch (const foveal::Error&) {}
  return 0;
}
