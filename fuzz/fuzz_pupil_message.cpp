// libFuzzer target: a live Pupil message (topic + msgpack payload, split at the first NUL byte)
// must decode into samples or be rejected, never crash.
#include "foveal/gaze/source.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t topic_size = nul ? static_cast<size_t>(nul - data) : 0;
  const std::string topic = nul ? std::string(reinterpret_cast<const char*>(data), topic_size) : "gaze.";
  const uint8_t* payload = nul ? nul + 1 : data;
  const size_t payload_size = nul ? size - topic_size - 1 : size;
  std::vector<foveal::GazeSample> out;
  foveal::decode_pupil_message(topic, payload, payload_size, {640, 480}, 0.6f, out);
  return 0;
}
